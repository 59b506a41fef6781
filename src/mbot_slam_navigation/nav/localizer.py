"""When amcl updates its filter, ROS-free: shared by the amcl node and bench/bench_amcl.py.

As ROS amcl: the first scan after (re)initialization weighs the particles without motion; later
scans update the filter once odometry has moved more than update_min_d along x or y, or turned more
than update_min_a, since the last update (or once a no-motion update was requested); every
resample_interval-th update resamples. Poses are (x [m], y [m], yaw [rad]): odometry poses are the
base in the odom frame, the estimate the base in the map frame.
"""
from typing import Optional, Tuple

import numpy as np

from mbot_slam_navigation.transforms import compose2d, inverse2d, normalize_angle

Pose = Tuple[float, float, float]


class Localizer:
    def __init__(self, pf, update_min_d: float, update_min_a: float, resample_interval: int):
        self.pf = pf                     # _core._Amcl with a map
        self.update_min_d, self.update_min_a = update_min_d, update_min_a
        self.resample_interval = resample_interval
        self.odom_at_update: Optional[Pose] = None
        self.force_update = False
        self.updates = 0

    def reinitialized(self) -> None:
        """The particles were replaced (initial pose, global localization, new map)."""
        self.odom_at_update = None

    def due(self, odom: Pose) -> bool:
        if self.odom_at_update is None or self.force_update:
            return True
        dx, dy = odom[0] - self.odom_at_update[0], odom[1] - self.odom_at_update[1]
        da = normalize_angle(odom[2] - self.odom_at_update[2])
        return abs(dx) > self.update_min_d or abs(dy) > self.update_min_d or abs(da) > self.update_min_a

    def update(self, odom: Pose, angle_min: float, angle_increment: float, range_min: float, range_max: float,
               ranges: np.ndarray, laser_xy: Tuple[float, float]) -> bool:
        """Feeds one scan taken at odometry pose `odom`; returns True when the filter was updated.
        Angles are in the base frame; the laser sits at laser_xy in the base frame."""
        if not self.due(odom):
            return False
        if self.odom_at_update is not None:
            self.pf.motion_update(np.asarray(self.odom_at_update, float), np.asarray(odom, float))
        self.force_update = False
        self.pf.sensor_update(angle_min, angle_increment, range_min, range_max, np.asarray(ranges, np.float32),
                              np.array([laser_xy[0], laser_xy[1], 0.0]))
        self.odom_at_update = tuple(odom)
        self.updates += 1
        if self.updates % self.resample_interval == 0:
            self.pf.resample()
        return True

    def estimate(self):
        """(pose, covariance 3x3, share of the weight in the best cluster, clusters)."""
        mean, cov, weight, clusters = self.pf.estimate()
        return (float(mean[0]), float(mean[1]), float(mean[2])), cov, weight, clusters

    def map_to_odom(self, estimate: Pose) -> Pose:
        """map -> odom = (map -> base) * (odom -> base)^-1, at the last update."""
        return compose2d(estimate, inverse2d(self.odom_at_update))
