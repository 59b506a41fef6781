"""Typed wrapper over the C++ RBPF SLAM, configured with slam_gmapping's parameter names."""
import difflib
from typing import Dict, Tuple

import numpy as np

from mbot_slam_navigation import _core

# slam_gmapping's parameters that shape the filter, with ROS's defaults.
GMAPPING_DEFAULTS = {
    'maxUrange': 80.0, 'maxRange': 80.0, 'sigma': 0.05, 'kernelSize': 1, 'lstep': 0.05, 'astep': 0.05,
    'iterations': 5, 'lsigma': 0.075, 'ogain': 3.0, 'lskip': 0, 'minimumScore': 0.0, 'srr': 0.1, 'srt': 0.2,
    'str': 0.1, 'stt': 0.2, 'linearUpdate': 1.0, 'angularUpdate': 0.5, 'temporalUpdate': -1.0,
    'resampleThreshold': 0.5, 'particles': 30, 'xmin': -100.0, 'ymin': -100.0, 'xmax': 100.0, 'ymax': 100.0,
    'delta': 0.05, 'llsamplerange': 0.01, 'llsamplestep': 0.01, 'lasamplerange': 0.005, 'lasamplestep': 0.005,
    'seed': 0,
}


def make_params(overrides: Dict[str, float], laser_pose=(0.0, 0.0, 0.0)):
    """_RbpfParams from gmapping-named values; an unknown name raises KeyError with the nearest one."""
    for key in overrides:
        if key not in GMAPPING_DEFAULTS:
            near = difflib.get_close_matches(key, GMAPPING_DEFAULTS, n=1)
            raise KeyError('unknown SLAM parameter "%s"%s' % (key, ' (did you mean "%s"?)' % near[0] if near else ''))
    v = dict(GMAPPING_DEFAULTS, **overrides)
    p = _core._RbpfParams()
    p.particles, p.linear_update, p.angular_update = int(v['particles']), v['linearUpdate'], v['angularUpdate']
    p.temporal_update, p.resample_threshold, p.ogain = v['temporalUpdate'], v['resampleThreshold'], v['ogain']
    p.minimum_score, p.delta = v['minimumScore'], v['delta']
    p.llsamplerange, p.llsamplestep = v['llsamplerange'], v['llsamplestep']
    p.lasamplerange, p.lasamplestep = v['lasamplerange'], v['lasamplestep']
    p.xmin, p.ymin, p.xmax, p.ymax = v['xmin'], v['ymin'], v['xmax'], v['ymax']
    p.seed = int(v['seed'])
    motion = _core._MotionModelParams()
    motion.srr, motion.srt, motion.str, motion.stt = v['srr'], v['srt'], v['str'], v['stt']
    p.motion = motion
    m = _core._ScanMatcherParams()
    m.sigma, m.kernel_size, m.lstep, m.astep = v['sigma'], int(v['kernelSize']), v['lstep'], v['astep']
    m.iterations, m.lsigma, m.lskip = int(v['iterations']), v['lsigma'], int(v['lskip'])
    m.max_urange, m.max_range = v['maxUrange'], v['maxRange']
    m.laser_pose = np.asarray(laser_pose, float)
    p.matcher = m
    p.validate()
    return p


class RbpfSlam:
    """GMapping-style SLAM; poses are base in map (x [m], y [m], yaw [rad])."""

    def __init__(self, params=None, laser_pose=(0.0, 0.0, 0.0), **gmapping_params):
        self._impl = _core._RbpfSlam(params or make_params(gmapping_params, laser_pose))

    def process_scan(self, odom, angle_min, angle_increment, range_min, range_max, ranges, time) -> bool:
        return self._impl.process_scan(np.asarray(odom, float), angle_min, angle_increment, range_min, range_max,
                                       np.asarray(ranges, np.float32), time)

    def current_pose(self) -> Tuple[float, float, float]:
        return tuple(float(v) for v in self._impl.current_pose())

    def best_trajectory(self) -> np.ndarray:
        """(N, 7): time, pose x y yaw (map), odometry x y yaw, one row per filter update."""
        return self._impl.best_trajectory()

    def best_map(self, occ_thresh: float = 0.25):
        """(data (H, W) int8 with -1/0/100, origin (x, y) [m], resolution [m])."""
        data, origin, res = self._impl.best_map(occ_thresh)
        return data, (float(origin[0]), float(origin[1])), res

    @property
    def updates(self) -> int:
        return self._impl.updates

    @property
    def resamples(self) -> int:
        return self._impl.resamples

    def map_memory(self) -> Tuple[int, int]:
        """(bytes the particles' maps hold, bytes they would hold if no patch were shared)."""
        return self._impl.map_memory()
