"""Planar poses and grids as ROS messages, one way for every node: (x [m], y [m], yaw [rad]) to and
from geometry_msgs/Pose, and a row-major int8 grid (row 0 = lowest y) as nav_msgs/OccupancyGrid."""
from typing import Sequence, Tuple

import numpy as np
from geometry_msgs.msg import Pose
from nav_msgs.msg import OccupancyGrid

from mbot_slam_navigation.transforms import quaternion_to_yaw, yaw_to_quaternion


def pose_msg(x: float, y: float, yaw: float) -> Pose:
    p = Pose()
    p.position.x, p.position.y = float(x), float(y)
    o = p.orientation
    o.x, o.y, o.z, o.w = yaw_to_quaternion(yaw)
    return p


def pose_from_msg(p: Pose) -> Tuple[float, float, float]:
    q = p.orientation
    return p.position.x, p.position.y, quaternion_to_yaw(q.x, q.y, q.z, q.w)


def occupancy_grid_msg(data: np.ndarray, resolution: float, origin: Sequence[float], frame_id: str,
                       stamp) -> OccupancyGrid:
    """`data` (height, width) occupancy values; `origin` the lower-left corner (x, y[, yaw])."""
    msg = OccupancyGrid()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    msg.info.map_load_time = stamp
    msg.info.resolution = resolution
    msg.info.height, msg.info.width = data.shape
    msg.info.origin = pose_msg(origin[0], origin[1], origin[2] if len(origin) > 2 else 0.0)
    msg.data = np.asarray(data).ravel().tolist()  # int8[]: rospy packs a sequence of ints
    return msg
