"""CARMEN log reading (FLASER, ODOM, ROBOTLASER1; plain or .bz2) into scans with odometry.

Each scan: time [s] (the ipc timestamp, which relation files use), the robot's odometry pose
(x, y, theta) and the laser's pose in the robot frame, angles and ranges [m]. Returns of ~81.9 m
mean "no measurement" in these logs (no echo, or glass); they are kept as they are, so that SLAM's
maxRange (80 m by default) skips them as gmapping does, rather than clearing the map along them.
"""
import bz2
import math
from dataclasses import dataclass
from typing import List, Tuple

import numpy as np

from mbot_slam_navigation.transforms import relative2d


class CarmenError(ValueError):
    """A line that cannot be read; the message names the file and line."""


@dataclass
class Scan:
    time: float
    odom: Tuple[float, float, float]        # robot in odom (x [m], y [m], theta [rad])
    laser_pose: Tuple[float, float, float]  # laser in the robot frame
    angle_min: float                        # [rad]
    angle_increment: float                  # [rad]
    ranges: np.ndarray                      # float32 [m]


def read_log(path: str) -> List[Scan]:
    opener = bz2.open if path.endswith('.bz2') else open
    scans = []
    with opener(path, 'rt') as f:
        for lineno, line in enumerate(f, 1):
            parts = line.split()
            if not parts or parts[0] not in ('FLASER', 'ROBOTLASER1'):
                continue
            try:
                if parts[0] == 'FLASER':
                    n = int(parts[1])
                    vals = [float(v) for v in parts[2:2 + n + 6]]
                    ranges, laser, odom = vals[:n], vals[n:n + 3], vals[n + 3:n + 6]
                    t = float(parts[2 + n + 6])
                    inc = math.pi / (n - 1) if n % 2 == 1 else math.pi / n
                    start = -math.pi / 2
                else:
                    start, inc = float(parts[2]), float(parts[4])  # parts[3]: field of view
                    n = int(parts[8])
                    ranges = [float(v) for v in parts[9:9 + n]]
                    k = 9 + n
                    nrem = int(parts[k])
                    k += 1 + nrem
                    laser = [float(v) for v in parts[k:k + 3]]
                    odom = [float(v) for v in parts[k + 3:k + 6]]
                    t = float(parts[k + 11])
                if len(ranges) != n:
                    raise ValueError('%d ranges announced, %d present' % (n, len(ranges)))
            except (ValueError, IndexError) as e:
                raise CarmenError('%s:%d: cannot read %s line: %s' % (path, lineno, parts[0], e)) from None
            scans.append(Scan(time=t, odom=tuple(odom), laser_pose=relative2d(odom, laser), angle_min=start,
                              angle_increment=inc, ranges=np.asarray(ranges, dtype=np.float32)))
    if not scans:
        raise CarmenError('%s: no FLASER or ROBOTLASER1 lines' % path)
    return scans
