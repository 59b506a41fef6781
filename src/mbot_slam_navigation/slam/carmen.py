"""CARMEN log reading (FLASER, ODOM, ROBOTLASER1; plain or .bz2) into scans with odometry.

Each scan: time [s] (the ipc timestamp, which relation files use), the robot's odometry pose
(x, y, theta) and the laser's pose in the robot frame, angles and ranges [m]. Returns of ~81.9 m
mean "no measurement" in these logs (no echo, or glass); they are kept as they are, so that SLAM's
maxRange (80 m by default) skips them as gmapping does, rather than clearing the map along them.
"""
import bz2
import math
from dataclasses import dataclass
from typing import List, Optional, Tuple

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
    range_max: Optional[float] = None       # [m] the sensor's, where the log says it (a bag's LaserScan)


def _text_lines(path: str):
    """The log's lines (plain or .bz2); CarmenError naming the file when it is not text at all (a
    binary file, a bag under another name, a broken .bz2), with what was expected and found."""
    try:
        with (bz2.open if path.endswith('.bz2') else open)(path, 'rb') as f:
            head = f.read(4096)
    except (OSError, EOFError) as e:
        raise CarmenError('%s: cannot be read as %s: %s' % (path, 'a bzip2 file' if path.endswith('.bz2') else 'a file', e)) from None
    if head.startswith(b'#ROSBAG'):
        raise CarmenError('%s: is a rosbag, not a CARMEN log (name it .bag to read it as one)' % path)
    try:
        head.decode('ascii')
        binary = b'\0' in head
    except UnicodeDecodeError:
        binary = True
    if binary:
        raise CarmenError('%s: not a CARMEN log: expected text lines (FLASER, ROBOTLASER1, ODOM, ...), found binary '
                          'data (first bytes %s)' % (path, head[:8].hex(' ')))
    opener = bz2.open if path.endswith('.bz2') else open
    with opener(path, 'rt', encoding='ascii', errors='replace') as f:
        yield from f


def read_log(path: str) -> List[Scan]:
    """The scans of a CARMEN log; CarmenError (a ValueError) naming the file, and the line where
    one is at fault, when the log cannot be used."""
    scans = []
    for lineno, line in enumerate(_text_lines(path), 1):
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
