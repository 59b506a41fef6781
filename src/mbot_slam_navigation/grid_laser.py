"""grid_laser: a laser scanner simulated in a rectangular room drawn into an occupancy grid.

A simulator-less smoke source for the mapping pipeline. The room spans [0, ~room_width] x
[0, ~room_height] metres in ~world_frame (walls one cell thick); the sensor's pose is whatever tf
says for ~frame_id in ~world_frame, so a static_transform_publisher places it. Publishes
sensor_msgs/LaserScan on ``scan`` at ~rate Hz with REP 117 ranges (+inf for no return).
"""
import math

import numpy as np
import rospy
import tf2_ros
from sensor_msgs.msg import LaserScan

from mbot_slam_navigation.grid import OccupancyGrid
from mbot_slam_navigation.transforms import quaternion_to_yaw


def make_room(width_m: float, height_m: float, resolution_m: float) -> OccupancyGrid:
    """A grid covering the room plus one cell each side, with the walls' cells occupied."""
    nx = int(round(width_m / resolution_m)) + 2
    ny = int(round(height_m / resolution_m)) + 2
    grid = OccupancyGrid(nx, ny, resolution_m, origin=(-resolution_m, -resolution_m))
    for x in range(nx):
        for y in range(ny):
            grid.set_occupied((x, y), x in (0, nx - 1) or y in (0, ny - 1))
    return grid


def main() -> None:
    rospy.init_node('grid_laser')
    width = rospy.get_param('~room_width', 4.0)       # [m]
    height = rospy.get_param('~room_height', 3.0)     # [m]
    resolution = rospy.get_param('~resolution', 0.05)  # [m]
    world_frame = rospy.get_param('~world_frame', 'map')
    frame_id = rospy.get_param('~frame_id', 'laser')
    beams = rospy.get_param('~samples', 360)
    range_max = rospy.get_param('~range_max', 6.0)    # [m]
    rate_hz = rospy.get_param('~rate', 10.0)          # [Hz]
    for key, value in (('room_width', width), ('room_height', height), ('resolution', resolution),
                       ('samples', beams), ('range_max', range_max), ('rate', rate_hz)):
        if not value > 0:
            rospy.logfatal('grid_laser: ~%s must be positive, got %r', key, value)
            return

    room = make_room(width, height, resolution)
    angle_increment = 2.0 * math.pi / beams
    angles_in_sensor = -math.pi + angle_increment * np.arange(beams)
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    pub = rospy.Publisher('scan', LaserScan, queue_size=5)
    rate = rospy.Rate(rate_hz)
    while not rospy.is_shutdown():
        try:
            tf = buffer.lookup_transform(world_frame, frame_id, rospy.Time(0), rospy.Duration(1.0))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(5.0, 'grid_laser: no transform from %s to %s: %s', frame_id, world_frame, e)
            continue
        t, q = tf.transform.translation, tf.transform.rotation
        yaw = quaternion_to_yaw(q.x, q.y, q.z, q.w)
        ranges = room.cast_rays(t.x, t.y, angles_in_sensor + yaw, range_max)
        scan = LaserScan()
        scan.header.stamp = rospy.Time.now()
        scan.header.frame_id = frame_id
        scan.angle_min = -math.pi
        scan.angle_max = -math.pi + angle_increment * (beams - 1)
        scan.angle_increment = angle_increment
        scan.range_min = 0.05
        scan.range_max = range_max
        scan.ranges = ranges.astype(np.float32).tolist()
        pub.publish(scan)
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break
