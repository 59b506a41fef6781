"""Typed wrappers over the two C++ SLAM backends, configured with the slam_gmapping node's names.

`make_slam('rbpf' | 'graph', {name: value}, laser_pose)` builds either; both offer process_scan,
current_pose, trajectory, occupancy and updates (core/slam_backend.h). Poses are the base in the
map frame (x [m], y [m], yaw [rad]).
"""
from typing import Dict, Tuple

import numpy as np

from mbot_slam_navigation import _core

BACKENDS = ('graph', 'rbpf')
DEFAULT_BACKEND = 'graph'  # the better on the Radish logs (bench/bench_slam.py)
# [m] maxUrange and maxRange when not given: a log has no range_max to take them from (the node
# takes the scan's).
OFFLINE_MAX_RANGE = 80.0


def read_config(values: Dict[str, float], backend: str, laser_pose=(0.0, 0.0, 0.0)):
    """slam_gmapping's parameters from node-named values (core/slam_config.h: the node's reader,
    names and defaults); a name the backend does not read raises KeyError naming the nearest one."""
    if backend not in BACKENDS:
        raise ValueError('unknown SLAM backend "%s": use one of %s' % (backend, ', '.join(BACKENDS)))
    said = []
    config, unknown = _core.read_slam_config(dict(values, backend=backend), '/slam_offline', said.append,
                                             OFFLINE_MAX_RANGE)
    for key in unknown:
        why = next((w for w in said if '/%s ' % key in w), '')
        raise KeyError('unknown %s SLAM parameter "%s"%s' % (backend, key, (': ' + why) if why else ''))
    rbpf, graph = config.rbpf, config.graph
    rbpf.matcher.laser_pose = np.asarray(laser_pose, float)
    rbpf.share_with(graph)
    rbpf.tracking = graph
    return rbpf, graph


def make_params(overrides: Dict[str, float], laser_pose=(0.0, 0.0, 0.0)):
    """_RbpfParams from gmapping-named values; an unknown name raises KeyError with the nearest one."""
    p, _ = read_config(overrides, 'rbpf', laser_pose)
    p.validate()
    return p


def make_graph_params(overrides: Dict[str, float], laser_pose=(0.0, 0.0, 0.0), background=False):
    """_GraphSlamParams from node-named values (offline runs are synchronous unless asked)."""
    _, p = read_config(overrides, 'graph', laser_pose)
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

    def save_session(self, filename: str) -> str:
        """Writes the session to <filename>.posegraph (atomically); returns that path."""
        path = _core.session_path(filename)
        self._impl.save_session(path)
        return path

    @classmethod
    def load_session(cls, filename: str, params=None, laser_pose=(0.0, 0.0, 0.0), background=False, **graph_params):
        """(GraphSlam holding the session <filename>.posegraph, notes on parameters that differ from
        the session's). Raises _core.SessionError (a ValueError) naming the file and what is wrong."""
        slam = cls.__new__(cls)
        slam._impl, notes = _core._GraphSlam.load_session(
            _core.session_path(filename), params or make_graph_params(graph_params, laser_pose, background))
        return slam, notes

    def resume(self, pose=None, localization: bool = False) -> None:
        """How the next scans join a loaded session: near `pose` (x, y, yaw in its map), or anywhere
        (global matching) without; with `localization` the graph does not grow."""
        self._impl.resume(None if pose is None else [float(v) for v in pose], localization)

    def resuming(self) -> bool:
        return self._impl.resuming()

    def resume_failure(self) -> str:
        return self._impl.resume_failure()

    def first_pose(self) -> Tuple[float, float, float]:
        return self._impl.first_pose()


def make_slam(backend: str, params: Dict[str, float], laser_pose=(0.0, 0.0, 0.0), background=False):
    """background: the graph's loop closure in its own thread, as the node runs it (the particle
    filter has none)."""
    if backend not in BACKENDS:
        raise ValueError('unknown SLAM backend "%s": use one of %s' % (backend, ', '.join(BACKENDS)))
    if backend == 'graph':
        return GraphSlam(laser_pose=laser_pose, background=background, **params)
    return RbpfSlam(laser_pose=laser_pose, **params)
