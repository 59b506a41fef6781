"""Costmap2DROS: a LayeredCostmap fed by ROS topics and tf2, published for rviz.

Subscribes the static layer's map topic (nav_msgs/OccupancyGrid, latched or repeated, so it follows
a growing SLAM map) and each LaserScan observation source; looks the robot and the sensors up in tf2
in ``global_frame``; publishes ``~<name>/costmap`` (nav_msgs/OccupancyGrid), ``~<name>/costmap_updates``
(map_msgs/OccupancyGridUpdate) and ``~<name>/footprint`` (geometry_msgs/PolygonStamped).
"""
import math
import threading
from typing import Optional, Tuple

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import Point32, PolygonStamped
from map_msgs.msg import OccupancyGridUpdate
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import LaserScan

from mbot_slam_navigation.nav.costmap import CostmapConfig, LayeredCostmap
from mbot_slam_navigation.ros_msgs import occupancy_grid_msg
from mbot_slam_navigation.sim_heartbeat import Heartbeat
from mbot_slam_navigation.transforms import quaternion_to_yaw


def _warn(msg: str) -> None:
    rospy.logwarn(msg)


class CostmapROS:
    def __init__(self, name: str, tf_buffer: tf2_ros.Buffer, node_ns: str = '~'):
        self.name = name
        self.tf = tf_buffer
        values = rospy.get_param('%s%s' % (node_ns, name), {})
        self.config = CostmapConfig(name, values, _warn, ns_prefix=rospy.get_name())
        self.layered = LayeredCostmap(self.config, _warn)
        self.lock = threading.RLock()
        self.robot_pose = None
        self.last_update = None
        self.tf_problem = ''
        self.heartbeat = Heartbeat()  # how current the robot pose is, for the simulator's auto pacing
        self.ever_updated = False
        self.update_seq = 0
        self.costmap_pub = rospy.Publisher('~%s/costmap' % name, OccupancyGrid, queue_size=1, latch=True)
        self.updates_pub = rospy.Publisher('~%s/costmap_updates' % name, OccupancyGridUpdate, queue_size=1)
        self.footprint_pub = rospy.Publisher('~%s/footprint' % name, PolygonStamped, queue_size=1)
        self.subscribers = []
        if self.config.static is not None:
            topic = self.config.static['map_topic']
            self.subscribers.append(rospy.Subscriber(topic, OccupancyGrid, self._on_map, queue_size=1))
            rospy.loginfo('%s: static layer waits for a map on %s', name, rospy.resolve_name(topic))
        if self.config.obstacle is not None:
            for source_name, src in self.config.obstacle['sources'].items():
                self.subscribers.append(rospy.Subscriber(src.topic, LaserScan, self._on_scan, callback_args=source_name,
                                                         queue_size=5))
        self.active = True
        self.stopped = False
        self._timers = []
        if self.config.update_frequency > 0:
            self._timers.append(rospy.Timer(rospy.Duration(1.0 / self.config.update_frequency), self._update_tick))
        if self.config.publish_frequency > 0:
            self._timers.append(rospy.Timer(rospy.Duration(1.0 / self.config.publish_frequency), self._publish_tick))

    # --- inputs ------------------------------------------------------------------------------------
    def _on_map(self, msg: OccupancyGrid) -> None:
        info = msg.info
        if info.width == 0 or info.height == 0 or len(msg.data) != info.width * info.height:
            rospy.logerr_throttle(10, '%s: map on %s has %d cells for %d x %d; ignored' % (
                self.name, self.subscribers[0].name, len(msg.data), info.width, info.height))
            return
        frame = msg.header.frame_id.lstrip('/')
        if frame and frame != self.config.global_frame:
            rospy.logwarn_throttle(30, '%s: the map is in frame "%s" but global_frame is "%s"; used as if it were in %s'
                                   % (self.name, frame, self.config.global_frame, self.config.global_frame))
        q = info.origin.orientation
        if abs(quaternion_to_yaw(q.x, q.y, q.z, q.w)) > 1e-6:
            rospy.logwarn_throttle(30, '%s: the map origin is rotated; costmaps use its position only' % self.name)
        data = np.asarray(msg.data, np.int8).reshape(info.height, info.width)
        with self.lock:
            self.layered.set_map(data, (info.origin.position.x, info.origin.position.y), info.resolution)

    def _on_scan(self, msg: LaserScan, source_name: str) -> None:
        src = self.config.obstacle['sources'][source_name]
        frame = (src.sensor_frame or msg.header.frame_id).lstrip('/')
        try:
            t = self.tf.lookup_transform(self.config.global_frame, frame, msg.header.stamp, rospy.Duration(0.2))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(5, '%s: observation source %s (topic %s): no transform from "%s" to "%s" at the scan '
                                   'time: %s' % (self.name, source_name, src.topic, frame, self.config.global_frame, e))
            return
        tr, q = t.transform.translation, t.transform.rotation
        pose = (tr.x, tr.y, quaternion_to_yaw(q.x, q.y, q.z, q.w))
        with self.lock:
            self.layered.add_scan(source_name, msg.header.stamp.to_sec(), pose, tr.z, msg.angle_min,
                                  msg.angle_increment, msg.range_min, msg.range_max, msg.ranges)

    # --- robot pose --------------------------------------------------------------------------------
    def lookup_robot_pose(self) -> Optional[Tuple[float, float, float]]:
        """The robot's (x, y, yaw) in global_frame, or None (reason in ``tf_problem``)."""
        c = self.config
        try:
            t = self.tf.lookup_transform(c.global_frame, c.robot_base_frame, rospy.Time(0), rospy.Duration(0.1))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            self.tf_problem = 'no transform from %s to %s: %s' % (c.robot_base_frame, c.global_frame, e)
            return None
        self.heartbeat.beat(t.header.stamp)
        age = (rospy.Time.now() - t.header.stamp).to_sec()
        if t.header.stamp != rospy.Time(0) and age > c.transform_tolerance:
            self.tf_problem = ('the transform from %s to %s is %.2f s old, more than transform_tolerance %.2f s'
                               % (c.robot_base_frame, c.global_frame, age, c.transform_tolerance))
            return None
        self.tf_problem = ''
        q = t.transform.rotation
        return (t.transform.translation.x, t.transform.translation.y, quaternion_to_yaw(q.x, q.y, q.z, q.w))

    # --- update and publish ------------------------------------------------------------------------
    def _update_tick(self, _event) -> None:
        if self.active:
            self.update()

    def update(self) -> bool:
        pose = self.lookup_robot_pose()
        if pose is None:
            rospy.logwarn_throttle(5, '%s: not updated: %s' % (self.name, self.tf_problem))
            return False
        with self.lock:
            if not self.layered.ready:
                rospy.logwarn_throttle(10, '%s: waiting for the first map on %s' % (
                    self.name, rospy.resolve_name(self.config.static['map_topic'])))
                return False
            self.robot_pose = pose
            self.layered.update(pose)
            self.last_update = rospy.Time.now()
            self.ever_updated = True
            self.update_seq += 1
        self._publish_footprint(pose)
        return True

    def is_current(self) -> Tuple[bool, str]:
        """(current, why not): stale sensors or a costmap that never updated."""
        if not self.ever_updated:
            return False, '%s has not been updated yet%s' % (self.name, ': ' + self.tf_problem if self.tf_problem else '')
        stale = self.layered.stale_sources(rospy.Time.now().to_sec())
        if stale:
            return False, '%s: observation source(s) %s not updated within their expected_update_rate' % (
                self.name, ', '.join(stale))
        return True, ''

    def _publish_tick(self, _event) -> None:
        if self.active and self.ever_updated:
            self.publish()

    def publish(self) -> None:
        with self.lock:
            # The geometry of the grid that was computed, not the layered costmap's: a new map
            # resizes the latter at once, the former only at the next update.
            core = self.layered.core
            data = core.occupancy_data()
            geometry = ((core.height, core.width), tuple(core.origin), core.resolution)
        stamp = rospy.Time.now()
        h, w = geometry[0]
        # The full grid every time (so a latecomer to the latched topic sees a current one), and the
        # same as an update message for clients that follow costmap_updates like rviz does.
        msg = occupancy_grid_msg(data.reshape(h, w), geometry[2], geometry[1], self.config.global_frame, stamp)
        self.costmap_pub.publish(msg)
        if self.updates_pub.get_num_connections() > 0:
            up = OccupancyGridUpdate()
            up.header = msg.header
            up.x, up.y, up.width, up.height = 0, 0, w, h
            up.data = msg.data
            self.updates_pub.publish(up)

    def _publish_footprint(self, pose) -> None:
        if self.footprint_pub.get_num_connections() == 0:
            return
        msg = PolygonStamped()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id = self.config.global_frame
        c, s = math.cos(pose[2]), math.sin(pose[2])
        for (x, y) in self.config.footprint:
            msg.polygon.points.append(Point32(pose[0] + c * x - s * y, pose[1] + s * x + c * y, 0.0))
        self.footprint_pub.publish(msg)

    # --- control -----------------------------------------------------------------------------------
    def reset_layers(self, keep_window=None) -> None:
        with self.lock:
            self.layered.reset_obstacles(keep_window)

    def stop(self) -> None:
        """shutdown_costmaps: no updates or sensor processing until start()."""
        self.active = False

    def start(self) -> None:
        self.active = True

    def snapshot(self):
        """(C++ costmap, robot pose) under the lock, for planning without racing the updater."""
        with self.lock:
            return self.layered.core, self.robot_pose
