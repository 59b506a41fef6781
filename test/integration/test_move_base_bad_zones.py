#!/usr/bin/env python3
"""Bad masks (move_base_bad_zones.test): the user is told what is wrong and where, and move_base
navigates without the filters (full speed in the living room, which the bad speed mask covers)."""
import glob
import math
import os
import threading
import time
import unittest

import numpy as np
import rospkg
import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from move_base_msgs.msg import MoveBaseAction
from nav_msgs.msg import OccupancyGrid, Odometry
from rosgraph_msgs.msg import Log

from mbot_slam_navigation.maps.map_io import load_map
from mbot_slam_navigation.nav.action_client import SimpleActionClient

from test_move_base_home import goal_msg

COARSE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'data', 'speed_mask_0.1m.yaml')


class MoveBaseBadZonesTest(unittest.TestCase):
    def test_bad_masks_are_reported_and_move_base_goes_on_without_them(self):
        lock = threading.Lock()
        logs, speeds = [], []

        def on_log(m):
            with lock:
                logs.append((m.level, m.name, m.msg))
        rospy.Subscriber('/rosout', Log, on_log, queue_size=200)
        rospy.Subscriber('/base_pose_ground_truth', Odometry,
                         lambda m: speeds.append(math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y)))
        client = SimpleActionClient('move_base', MoveBaseAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(120.0)), 'no move_base action server')
        # The missing keep-out file: map_server said so, naming it, and exited (its log of this run).
        server_log = glob.glob(os.path.join(rospkg.get_log_dir(), rospy.get_param('/run_id'),
                                            'keepout_filter_mask_server-*.log'))
        self.assertTrue(server_log)
        self.assertIn('map_server: /nonexistent/keepout.yaml: cannot be read', open(server_log[0]).read())
        # A mask at 0.1 m on the speed filter's topic (as its map_server sent at the start): refused,
        # naming the topic and both resolutions, once per mask received.
        m = load_map(COARSE)
        msg = OccupancyGrid()
        msg.header.frame_id = 'map'
        msg.info.resolution, msg.info.width, msg.info.height = m.resolution, m.data.shape[1], m.data.shape[0]
        msg.info.origin.position.x, msg.info.origin.position.y = m.origin[0], m.origin[1]
        msg.info.origin.orientation.w = 1.0
        msg.data = m.data.astype(np.int8).ravel().tolist()
        pub = rospy.Publisher('/speed_filter_mask', OccupancyGrid, queue_size=1, latch=True)
        pub.publish(msg)
        client.send_goal(goal_msg(-2.0, -2.0, math.pi))
        self.assertTrue(client.wait_for_result(rospy.Duration(120.0)))
        self.assertEqual(client.get_state(), GoalStatus.SUCCEEDED, client.get_goal_status_text())
        self.assertGreater(max(speeds), 0.2)  # the 30% speed zone is not applied
        end = time.monotonic() + 30.0  # the keep-out mask that never came is said after 10 s (wall)
        while time.monotonic() < end:
            with lock:
                if sum('no mask on /keepout_filter_mask after 10 s' in m for _, _, m in logs) >= 2:
                    break
            time.sleep(0.5)
        with lock:
            errors = [m for level, _, m in logs if level >= Log.ERROR]
            warnings = [m for level, _, m in logs if level == Log.WARN]
        # said when the mask arrives, or when the map does if the mask came first; not repeated
        resolution = [m for m in errors if 'speed_filter' in m and '/speed_filter_mask' in m and '0.1 m' in m
                      and '0.05 m' in m]
        self.assertIn(len(resolution), (1, 2), errors)
        self.assertEqual(len([m for m in warnings if 'no mask on /keepout_filter_mask after 10 s' in m]), 2,
                         warnings)  # once per costmap
        rospy.loginfo('bad masks: %s', resolution + [m for m in warnings if 'no mask' in m])


if __name__ == '__main__':
    rospy.init_node('move_base_bad_zones_test')
    rostest.rosrun('mbot_slam_navigation', 'move_base_bad_zones', MoveBaseBadZonesTest)
