"""Logs as a robot's topics: a CARMEN log written as a rosbag that slam_gmapping can be run on
with `rosbag play --clock`, and what a SLAM node published, measured as the robot sees it.

The bag has, per scan (stamped with the log's time [s]): `/tf` with odom -> base_link (the log's
odometry) and base_link -> laser (the laser's mounting), then `/scan` (sensor_msgs/LaserScan in the
laser frame, range_max as given, so that the logs' "no return" readings above it are out of range
as REP 117 says). The file is written to a temporary name and renamed, so a bag that exists is whole.
"""
import math
import os
from typing import Sequence

import numpy as np

from mbot_slam_navigation.transforms import compose2d, normalize_angle, yaw_to_quaternion


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
        for seq, s in enumerate(scans):
            stamp = rospy.Time.from_sec(s.time)
            tf = TFMessage(transforms=[_transform(stamp, odom_frame, base_frame, s.odom),
                                       _transform(stamp, base_frame, laser_frame, s.laser_pose)])
            bag.write('/tf', tf, stamp)
            msg = LaserScan()
            # numbered as a driver's publisher numbers them: slam_gmapping counts the gaps (scans
            # its full queue dropped) by header.seq
            msg.header.seq, msg.header.stamp, msg.header.frame_id = seq, stamp, laser_frame
            msg.angle_min, msg.angle_increment = s.angle_min, s.angle_increment
            msg.angle_max = s.angle_min + s.angle_increment * (len(s.ranges) - 1)
            msg.range_min, msg.range_max = 0.0, range_max
            msg.ranges = np.asarray(s.ranges, np.float32).tolist()
            bag.write('/scan', msg, stamp)
    os.replace(tmp, path)
    return len(scans)


def corrections_at_robot(publications: np.ndarray, odom_times: np.ndarray, odom_poses: np.ndarray) -> np.ndarray:
    """How far each publication of map -> odom moves the robot: (N-1, 3) rows of stamp [s],
    translation [m], |rotation| [rad], one per publication after the first.

    publications: (N, 4) rows of stamp, x, y, yaw in the order published; odom_times/odom_poses:
    the odometry (base in odom) over time. Both the publication and the one before it are applied
    to the odometry at the newer one's stamp (the nearest sample), so that the robot's own motion
    between their stamps does not count, and a rotation of map -> odom counts by how it moves the
    robot, not by how it moves the odom frame's far-away origin."""
    p = np.asarray(publications, float)
    if len(p) < 2:
        return np.zeros((0, 3))
    times = np.asarray(odom_times, float)
    k = np.clip(np.searchsorted(times, p[1:, 0]), 0, len(times) - 1)
    out = np.zeros((len(p) - 1, 3))
    for row, (i, j) in enumerate(zip(range(len(p) - 1), k)):
        before, after = compose2d(p[i, 1:4], odom_poses[j]), compose2d(p[i + 1, 1:4], odom_poses[j])
        out[row] = (p[i + 1, 0], math.hypot(after[0] - before[0], after[1] - before[1]),
                    abs(normalize_angle(after[2] - before[2])))
    return out
