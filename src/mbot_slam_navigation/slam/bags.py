"""Logs as a robot's topics: a CARMEN log written as a rosbag that slam_gmapping can be run on
with `rosbag play --clock`, and what a SLAM node published, read back as poses.

The bag has, per scan (stamped with the log's time [s]): `/tf` with odom -> base_link (the log's
odometry) and base_link -> laser (the laser's mounting), then `/scan` (sensor_msgs/LaserScan in the
laser frame, range_max as given, so that the logs' "no return" readings above it are out of range
as REP 117 says). The file is written to a temporary name and renamed, so a bag that exists is whole.
"""
import os
from typing import List, Sequence, Tuple

import numpy as np

from mbot_slam_navigation.transforms import normalize_angle, yaw_to_quaternion


def _transform(stamp, parent: str, child: str, pose: Sequence[float]):
    from geometry_msgs.msg import TransformStamped
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id, t.child_frame_id = parent, child
    t.transform.translation.x, t.transform.translation.y = pose[0], pose[1]
    q = yaw_to_quaternion(pose[2])
    t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = q
    return t


def write_scan_bag(scans, path: str, range_max: float = 80.0, odom_frame: str = 'odom',
                   base_frame: str = 'base_link', laser_frame: str = 'laser') -> int:
    """Writes `scans` (carmen.Scan) to the bag `path`; returns the number of scans written."""
    import rosbag
    import rospy
    from sensor_msgs.msg import LaserScan
    from tf2_msgs.msg import TFMessage
    tmp = path + '.part'
    with rosbag.Bag(tmp, 'w') as bag:
        for s in scans:
            stamp = rospy.Time.from_sec(s.time)
            tf = TFMessage(transforms=[_transform(stamp, odom_frame, base_frame, s.odom),
                                       _transform(stamp, base_frame, laser_frame, s.laser_pose)])
            bag.write('/tf', tf, stamp)
            msg = LaserScan()
            msg.header.stamp, msg.header.frame_id = stamp, laser_frame
            msg.angle_min, msg.angle_increment = s.angle_min, s.angle_increment
            msg.angle_max = s.angle_min + s.angle_increment * (len(s.ranges) - 1)
            msg.range_min, msg.range_max = 0.0, range_max
            msg.ranges = np.asarray(s.ranges, np.float32).tolist()
            bag.write('/scan', msg, stamp)
    os.replace(tmp, path)
    return len(scans)


def largest_jump(publications: np.ndarray) -> Tuple[float, float, float]:
    """The largest change of a published transform between consecutive publications.

    publications: (N, 4) rows of stamp [s], x, y, yaw, in the order published. Returns
    (translation [m], rotation [rad], stamp [s] of the larger translation jump)."""
    p = np.asarray(publications, float)
    if len(p) < 2:
        return 0.0, 0.0, float('nan')
    d = np.hypot(np.diff(p[:, 1]), np.diff(p[:, 2]))
    r = np.abs([normalize_angle(a) for a in np.diff(p[:, 3])])
    k = int(np.argmax(d))
    return float(d[k]), float(np.max(r)), float(p[k + 1, 0])


def corrections_above(publications: np.ndarray, threshold: float) -> List[Tuple[float, float]]:
    """(stamp [s], translation [m]) of every change between consecutive publications above
    `threshold` [m]."""
    p = np.asarray(publications, float)
    if len(p) < 2:
        return []
    d = np.hypot(np.diff(p[:, 1]), np.diff(p[:, 2]))
    return [(float(p[k + 1, 0]), float(d[k])) for k in np.flatnonzero(d > threshold)]

