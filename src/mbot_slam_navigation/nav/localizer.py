"""When amcl updates its filter, ROS-free: shared by the amcl node and bench/bench_amcl.py.

As ROS amcl: the first scan after (re)initialization weighs the particles without motion; later
scans update the filter once odometry has moved more than update_min_d along x or y, or turned more
than update_min_a, since the last update (or once a no-motion update was requested); every
resample_interval-th update resamples. Poses are (x [m], y [m], yaw [rad]): odometry poses are the
base in the odom frame, the estimate the base in the map frame.
"""
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from mbot_slam_navigation.transforms import compose2d, inverse2d, normalize_angle

Pose = Tuple[float, float, float]


@dataclass
class FitMonitor:
    """Notices when the scans stop fitting the map around the estimate (the robot carried elsewhere,
    'kidnapped'), whether or not recovery_alpha_* lets amcl recover by itself.

    Each update's scan fit (the share of returns near the map's walls at the heaviest particle,
    Amcl::lastScanFit) is averaged slowly (over ~50 updates) and quickly (over ~2); the robot counts
    as lost once the quick average has stayed below LOST_RATIO of the slow one for LOST_UPDATES
    updates, and found again above FOUND_RATIO of it. While lost the slow average is held, so that it
    keeps the level of a good fit to compare with."""
    SLOW_ALPHA = 0.02
    FAST_ALPHA = 0.5
    WARM_UP = 10          # updates before any judgement
    LOST_RATIO = 0.7
    FOUND_RATIO = 0.85
    LOST_UPDATES = 3
    slow: float = 0.0
    fast: float = 0.0
    updates: int = 0
    below: int = 0
    lost: bool = False

    def add(self, fit: float) -> Optional[str]:
        """Feeds one update's mean weight; returns 'lost' or 'found' when that changes, else None."""
        if not fit > 0.0:
            return None
        self.updates += 1
        self.fast = fit if self.updates == 1 else self.fast + self.FAST_ALPHA * (fit - self.fast)
        if not self.lost:
            self.slow = fit if self.updates == 1 else self.slow + self.SLOW_ALPHA * (fit - self.slow)
        if self.updates < self.WARM_UP:
            return None
        if not self.lost:
            self.below = self.below + 1 if self.fast < self.LOST_RATIO * self.slow else 0
            if self.below >= self.LOST_UPDATES:
                self.lost = True
                return 'lost'
        elif self.fast > self.FOUND_RATIO * self.slow:
            self.lost, self.below = False, 0
            return 'found'
        return None

    def ratio(self) -> float:
        return self.fast / self.slow if self.slow > 0 else 1.0


class Localizer:
    """search_radius > 0 (ours; ROS amcl only injects random particles, by recovery_alpha_*): when the
    FitMonitor says the robot is lost, the particles are spread around the last estimate (a normal
    of standard deviation search_radius / 2 in x and y, any heading), where a robot carried or
    pushed usually is; if the scans do not fit again within search_updates filter updates, over the
    whole map's free space, as global_localization does. A search near the last estimate first also
    keeps a symmetric building from sending the estimate to the mirror image of the true pose."""
    def __init__(self, pf, update_min_d: float, update_min_a: float, resample_interval: int,
                 search_radius: float = 0.0, search_updates: int = 20):
        self.pf = pf                     # _core._Amcl with a map
        self.update_min_d, self.update_min_a = update_min_d, update_min_a
        self.resample_interval = resample_interval
        self.search_radius, self.search_updates = search_radius, search_updates
        self.odom_at_update: Optional[Pose] = None
        self.force_update = False
        self.updates = 0
        self.fit = FitMonitor()
        self.fit_change: Optional[str] = None  # 'lost' or 'found' at the last update, else None
        self.search: Optional[str] = None      # while lost with a search: 'near', then 'global'
        self.search_change: Optional[str] = None  # 'near' or 'global' when a search step began at the last update
        self.search_from: Optional[Pose] = None   # the estimate the near search was centred on
        self.search_started = 0

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
        self.fit_change = self.fit.add(self.pf.last_scan_fit)
        self.updates += 1
        if self.updates % self.resample_interval == 0:
            self.pf.resample()
        self.search_change = None
        if self.search_radius > 0:
            self.follow_search()
        return True

    def follow_search(self) -> None:
        """Spreads the particles when the robot is lost (search_radius), widens the search when it stays lost."""
        if self.fit_change == 'found' or not self.fit.lost:
            self.search = None
            return
        if self.fit_change == 'lost':
            self.search_from = self.estimate()[0]
            sigma = 0.5 * self.search_radius
            self.pf.init_gaussian(np.asarray(self.search_from, float), np.diag([sigma ** 2, sigma ** 2, np.pi ** 2]),
                                  free_only=True)
            self.search = self.search_change = 'near'
        elif self.search == 'near' and self.updates - self.search_started >= self.search_updates:
            self.pf.init_uniform()
            self.search = self.search_change = 'global'
        else:
            return
        self.search_started = self.updates
        self.force_update = True  # weigh the new particles at the next scan, moving or not

    def estimate(self):
        """(pose, covariance 3x3, share of the weight in the best cluster, clusters)."""
        mean, cov, weight, clusters = self.pf.estimate()
        return (float(mean[0]), float(mean[1]), float(mean[2])), cov, weight, clusters

    def map_to_odom(self, estimate: Pose) -> Pose:
        """map -> odom = (map -> base) * (odom -> base)^-1, at the last update."""
        return compose2d(estimate, inverse2d(self.odom_at_update))
