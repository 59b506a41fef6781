"""Typed wrappers over the two C++ SLAM backends, configured with the slam_gmapping node's names.

`make_slam('rbpf' | 'graph', {name: value}, laser_pose)` builds either; both offer process_scan,
current_pose, trajectory, occupancy and updates (core/slam_backend.h). Poses are the base in the
map frame (x [m], y [m], yaw [rad]).
"""
import difflib
from typing import Dict, Tuple

import numpy as np

from mbot_slam_navigation import _core

# The parameters both backends read (slam_gmapping's names and ROS defaults).
COMMON_DEFAULTS = {
    'maxUrange': 80.0, 'maxRange': 80.0, 'linearUpdate': 1.0, 'angularUpdate': 0.5, 'temporalUpdate': -1.0,
    'xmin': -100.0, 'ymin': -100.0, 'xmax': 100.0, 'ymax': 100.0, 'delta': 0.05,
}
# The particle filter's own (gmapping's). srr, srt, str and stt are these on the wheels' odometry
# (scan_odometry 0); on the scan-matched track, unless given, a tenth of them
# (_core.scan_odometry_motion(), rbpf_slam.h).
GMAPPING_DEFAULTS = dict(COMMON_DEFAULTS, **{
    'sigma': 0.05, 'kernelSize': 1, 'lstep': 0.05, 'astep': 0.05, 'iterations': 5, 'lsigma': 0.075, 'ogain': 3.0,
    'lskip': 0, 'minimumScore': 0.0, 'srr': 0.1, 'srt': 0.2, 'str': 0.1, 'stt': 0.2, 'resampleThreshold': 0.5,
    'particles': 30, 'llsamplerange': 0.01, 'llsamplestep': 0.01, 'lasamplerange': 0.005, 'lasamplestep': 0.005,
    'seed': 0, 'scan_odometry': 1, 'threads': 2, 'best_switch_margin': 4.0,
})
# The pose graph's own (graph_slam.h; the node reads them under the same private names).
GRAPH_DEFAULTS = dict(COMMON_DEFAULTS, **{
    'linearUpdate': 0.5,  # a node every 0.5 m (graph_slam.h), half gmapping's
    'match_max_range': 30.0, 'match_sigma': 0.075, 'local_match_sigma': -1.0, 'local_map_nodes': 40, 'local_search_window': 0.15,
    'local_search_sigmas': 10.0, 'local_search_max_window': 0.3,
    'local_search_angle': 0.15, 'local_min_score': 0.25, 'local_prior_margin': 0.03,
    'local_prior_weight': 5.0, 'local_prior_points': 130.0, 'local_visible_only': 1, 'local_visible_side': 0, 'submap_nodes': 10, 'loop_search_radius': 1.0,
    'loop_search_growth': 0.01, 'loop_search_max_radius': 6.0, 'loop_search_reach': 2.0, 'loop_search_angle': 0.35,
    'loop_min_response': 0.55, 'loop_ambiguity': 0.9, 'loop_sigma_distance': 0.25, 'loop_visible_shift': 0.15, 'loop_candidates': 3, 'loop_recent_submap': 1, 'redundant_distance': 0.3,
    'redundant_angle': 0.5, 'loop_solve_chi2': 7.8, 'keep_trimmed_scans': 0,
})
BACKENDS = ('graph', 'rbpf')
DEFAULT_BACKEND = 'graph'  # the better on the Radish logs (bench/bench_slam.py)
INT_PARAMS = {'kernelSize', 'iterations', 'lskip', 'particles', 'seed', 'threads', 'local_map_nodes', 'submap_nodes',
              'loop_candidates'}
MOTION_PARAMS = ('srr', 'srt', 'str', 'stt')
BOOL_PARAMS = {'scan_odometry', 'local_visible_only', 'local_visible_side', 'loop_recent_submap', 'keep_trimmed_scans'}


def defaults_of(backend: str) -> Dict[str, float]:
    if backend not in BACKENDS:
        raise ValueError('unknown SLAM backend "%s": use one of %s' % (backend, ', '.join(BACKENDS)))
    return GRAPH_DEFAULTS if backend == 'graph' else GMAPPING_DEFAULTS


def _merged(defaults, overrides, backend):
    for key in overrides:
        if key not in defaults:
            near = difflib.get_close_matches(key, defaults, n=1)
            raise KeyError('unknown %s SLAM parameter "%s"%s' % (backend, key, ' (did you mean "%s"?)' % near[0] if near else ''))
    return dict(defaults, **overrides)


def _matcher(v, laser_pose):
    m = _core._ScanMatcherParams()
    for name, key in (('sigma', 'sigma'), ('lstep', 'lstep'), ('astep', 'astep'), ('lsigma', 'lsigma')):
        if key in v:
            setattr(m, name, v[key])
    for name, key in (('kernel_size', 'kernelSize'), ('iterations', 'iterations'), ('lskip', 'lskip')):
        if key in v:
            setattr(m, name, int(v[key]))
    m.max_urange, m.max_range = v['maxUrange'], v['maxRange']
    m.laser_pose = np.asarray(laser_pose, float)
    return m


def make_params(overrides: Dict[str, float], laser_pose=(0.0, 0.0, 0.0)):
    """_RbpfParams from gmapping-named values; an unknown name raises KeyError with the nearest one."""
    v = _merged(GMAPPING_DEFAULTS, overrides, 'rbpf')
    p = _core._RbpfParams()
    p.particles, p.linear_update, p.angular_update = int(v['particles']), v['linearUpdate'], v['angularUpdate']
    p.temporal_update, p.resample_threshold, p.ogain = v['temporalUpdate'], v['resampleThreshold'], v['ogain']
    p.minimum_score, p.delta = v['minimumScore'], v['delta']
    p.llsamplerange, p.llsamplestep = v['llsamplerange'], v['llsamplestep']
    p.lasamplerange, p.lasamplestep = v['lasamplerange'], v['lasamplestep']
    p.xmin, p.ymin, p.xmax, p.ymax = v['xmin'], v['ymin'], v['xmax'], v['ymax']
    p.seed, p.threads, p.best_switch_margin = int(v['seed']), int(v['threads']), v['best_switch_margin']
    p.scan_odometry = bool(v['scan_odometry'])
    motion = _core.scan_odometry_motion() if p.scan_odometry else _core._MotionModelParams()
    for key in MOTION_PARAMS:
        if key in overrides or not p.scan_odometry:
            setattr(motion, key, v[key])
    p.motion = motion
    p.matcher = _matcher(v, laser_pose)
    # The track's local SLAM: the graph's defaults (a node every 0.5 m unless linearUpdate is
    # given), as the node gives it.
    p.tracking = make_graph_params({k: v[k] for k in COMMON_DEFAULTS if k != 'linearUpdate' or k in overrides}, laser_pose)
    p.validate()
    return p


def make_graph_params(overrides: Dict[str, float], laser_pose=(0.0, 0.0, 0.0), background=False):
    """_GraphSlamParams from node-named values (offline runs are synchronous unless asked)."""
    v = _merged(GRAPH_DEFAULTS, overrides, 'graph')
    p = _core._GraphSlamParams()
    p.linear_update, p.angular_update, p.temporal_update = v['linearUpdate'], v['angularUpdate'], v['temporalUpdate']
    p.delta, p.xmin, p.ymin, p.xmax, p.ymax = v['delta'], v['xmin'], v['ymin'], v['xmax'], v['ymax']
    p.matcher = _matcher(v, laser_pose)
    for key in GRAPH_DEFAULTS:
        if key not in COMMON_DEFAULTS:
            setattr(p, key, bool(v[key]) if key in BOOL_PARAMS else int(v[key]) if key in INT_PARAMS else float(v[key]))
    p.background = background
    p.validate()
    return p


class _Backend:
    _impl = None

    def process_scan(self, odom, angle_min, angle_increment, range_min, range_max, ranges, time) -> bool:
        return self._impl.process_scan(np.asarray(odom, float), angle_min, angle_increment, range_min, range_max,
                                       np.asarray(ranges, np.float32), time)

    def current_pose(self) -> Tuple[float, float, float]:
        return tuple(float(v) for v in self._impl.current_pose())

    def trajectory(self) -> np.ndarray:
        """(N, 7): time, pose x y yaw (map), odometry x y yaw, one row per map update."""
        return self._impl.trajectory()

    def occupancy(self, occ_thresh: float = 0.25):
        """(data (H, W) int8 with -1/0/100, origin (x, y) [m], resolution [m])."""
        data, origin, res = self._impl.occupancy(occ_thresh)
        return data, (float(origin[0]), float(origin[1])), res

    def finish(self):
        """Waits for background work (the graph's optimizer); nothing for the particle filter."""

    @property
    def updates(self) -> int:
        return self._impl.updates


class RbpfSlam(_Backend):
    """GMapping-style particle filter."""

    def __init__(self, params=None, laser_pose=(0.0, 0.0, 0.0), **gmapping_params):
        self._impl = _core._RbpfSlam(params or make_params(gmapping_params, laser_pose))

    @property
    def resamples(self) -> int:
        return self._impl.resamples

    def map_memory(self) -> Tuple[int, int]:
        """(bytes the particles' maps hold, bytes they would hold if no patch were shared)."""
        return self._impl.map_memory()


class GraphSlam(_Backend):
    """Pose graph with loop closure."""

    def __init__(self, params=None, laser_pose=(0.0, 0.0, 0.0), background=False, **graph_params):
        self._impl = _core._GraphSlam(params or make_graph_params(graph_params, laser_pose, background))

    def finish(self):
        self._impl.flush()

    def scan_poses(self) -> np.ndarray:
        """(M, 4): time, pose x y yaw (map) of every tracked scan, as optimized."""
        return self._impl.scan_poses()

    def stats(self) -> dict:
        return self._impl.stats()

    def edges(self):
        """[(from, to, x, y, theta, is_closure)]: every edge of the graph, its measurement the pose of
        node `to` in node `from`'s frame ([m], [rad]); node indices as in trajectory()."""
        return self._impl.edges()

    def closures(self):
        """(from, to) node indices of the accepted loop closures."""
        return [(f, t) for f, t, _, _, _, closure in self.edges() if closure]


def make_slam(backend: str, params: Dict[str, float], laser_pose=(0.0, 0.0, 0.0), background=False):
    """background: the graph's loop closure in its own thread, as the node runs it (the particle
    filter has none)."""
    defaults_of(backend)
    if backend == 'graph':
        return GraphSlam(laser_pose=laser_pose, background=background, **params)
    return RbpfSlam(laser_pose=laser_pose, **params)
