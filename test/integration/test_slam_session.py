#!/usr/bin/env python3
"""SLAM sessions in the home (slam_session.test). Tests run in order.

1. The session is saved halfway through the exploration (~serialize_map), slam_gmapping killed and
   started again from it (~session_file): the file is written and small, the restarted node serves
   the saved map at once and finds the robot on it (within 0.1 m of the truth) by matching, and
   the exploration, continued on it, finishes into one map with the walls where the world has them.
2. The finished session saved again, slam_gmapping started in localization mode on it (the robot
   back at its dock, where the session began) stands in for amcl: move_base reaches the tutorial's
   nine points, checked against the simulator's ground truth.
3. On it, a patrol of the nine points in order (launch/patrol.launch), two rounds: 18 of 18.
4. A 2D Pose Estimate (initialpose) 0.3 m off places the robot again, found within 0.1 m.
"""
import math
import os
import re
import subprocess
import time
import unittest

import numpy as np
import rosnode
import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from tf2_ros import Buffer, TransformListener

from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.srv import SerializePoseGraph, SerializePoseGraphResponse
from explore_result import wait_for_report
from tutorial_points import reach_tutorial_points

HALF_S = 90.0        # [s] simulated exploration before the session is saved (the home takes 180-260 s)
WAIT_S = 300.0       # [s] wall, for each step
GOAL_TIMEOUT = 240.0  # [s] simulated, per tutorial point
XY_TOL = 0.1 + 0.1    # [m] xy_goal_tolerance, and localization on a map SLAM made


def known_m2(msg):
    data = np.asarray(msg.data, np.int8)
    return float(np.count_nonzero(data >= 0)) * msg.info.resolution ** 2


class SlamSessionTest(unittest.TestCase):
    contacts = []
    map = None
    truth = None
    node = None  # slam_gmapping as the test started it

    @classmethod
    def setUpClass(cls):
        rospy.Subscriber('/map', OccupancyGrid, cls.on_map, queue_size=1, buff_size=2 ** 24)
        rospy.Subscriber('/base_pose_ground_truth', Odometry, cls.on_truth, queue_size=1)
        rospy.Subscriber('/gazebo/contacts', Contact, cls.contacts.append)
        cls.tf = Buffer(rospy.Duration(30.0))
        cls.listener = TransformListener(cls.tf)
        cls.session = rospy.get_param('~session')

    @classmethod
    def tearDownClass(cls):
        cls.stop_node()

    @classmethod
    def on_map(cls, msg):
        cls.map = msg

    @classmethod
    def on_truth(cls, msg):
        cls.truth = msg

    @classmethod
    def stop_node(cls):
        if cls.node is not None and cls.node.poll() is None:
            cls.node.terminate()
            try:
                cls.node.wait(20.0)
            except subprocess.TimeoutExpired:
                cls.node.kill()
        cls.node = None

    def wait(self, what, ok, timeout=WAIT_S):
        end = time.monotonic() + timeout
        while not ok():
            if rospy.is_shutdown():
                self.fail('shut down waiting for %s' % what)
            if time.monotonic() > end:
                self.fail('%s: not within %.0f s (wall)' % (what, timeout))
            time.sleep(0.2)

    def pose_error(self, since=0.0):
        """[m] map -> base_footprint against the simulator's truth (the home's map frame is its
        world frame: the robot starts at the origin); inf when tf has none stamped since `since` [s]."""
        try:
            t = self.tf.lookup_transform('map', 'base_footprint', rospy.Time(0), rospy.Duration(1.0))
        except Exception:
            return math.inf
        if t.header.stamp.to_sec() < since:
            return math.inf
        p = self.truth.pose.pose.position
        return math.hypot(t.transform.translation.x - p.x, t.transform.translation.y - p.y)

    def save(self):
        """Saves the session; returns its size [MB]."""
        rospy.wait_for_service('/slam_gmapping/serialize_map', 30.0)
        save = rospy.ServiceProxy('/slam_gmapping/serialize_map', SerializePoseGraph)
        self.assertEqual(save(self.session).result, SerializePoseGraphResponse.RESULT_SUCCESS)
        path = self.session + '.posegraph'
        self.assertTrue(os.path.isfile(path))
        return os.path.getsize(path) / 1e6

    def restart(self, *params):
        """Kills slam_gmapping and starts it again with its parameters plus `params` (_name:=value)."""
        rosnode.kill_nodes(['/slam_gmapping'])
        self.wait('slam_gmapping gone', lambda: not rosnode.rosnode_ping('/slam_gmapping', max_count=1), 30.0)
        self.stop_node()
        type(self).map = None
        type(self).node = subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'slam_gmapping', '__name:=slam_gmapping',
                                            'scan:=/scan', '_session_file:=' + self.session] + list(params))

    def test_1_a_session_saved_and_continued_finishes_the_exploration(self):
        path = self.session + '.posegraph'
        if os.path.exists(path):
            os.remove(path)
        self.wait('half the exploration', lambda: self.map is not None and rospy.get_time() >= HALF_S)
        size_mb = self.save()
        self.assertLess(size_mb, 20.0)
        before = known_m2(self.map)
        started = time.monotonic()
        self.restart()
        # the saved map at once (the first scan publishes it), then the robot found on it
        self.wait('the saved map served again', lambda: self.map is not None, 60.0)
        map_s = time.monotonic() - started
        self.assertGreaterEqual(known_m2(self.map), 0.95 * before)
        self.wait('the robot found on the saved map', lambda: self.pose_error() < 0.1, 120.0)
        found_s = time.monotonic() - started
        rospy.loginfo('session: %.1f MB, %.0f m^2 known when saved; served again %.1f s and the robot found %.1f s '
                      'after the restart (wall)', size_mb, before, map_s, found_s)

        r = wait_for_report('slam_session_report', first_timeout=60.0)
        self.assertEqual(r['outcome'], 'complete')
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.95)
        self.assertGreaterEqual(r['walls_within_tolerance'], 0.99)
        self.assertEqual(r['collisions'], 0)
        self.assertEqual(self.contacts, [])
        rospy.loginfo('continued exploration: %.0f s simulated, coverage %.1f%%, walls %.1f%% within 0.1 m',
                      r['exploration_time_s'], 100 * r['coverage_of_reachable_free'], 100 * r['walls_within_tolerance'])

    def test_2_localization_on_the_session_takes_move_base_to_the_tutorial_points(self):
        self.save()
        self.restart('_mode:=localization', '_map_start_at_dock:=true')
        self.wait('the robot localized at its dock', lambda: self.pose_error() < 0.1, 120.0)
        reach_tutorial_points(self, lambda: self.truth.pose.pose.position, GOAL_TIMEOUT, XY_TOL)
        self.assertLess(self.pose_error(), 0.1)
        self.assertEqual(self.contacts, [])

    def test_4_a_2d_pose_estimate_places_the_robot_again(self):
        """rviz's 2D Pose Estimate (initialpose) while localizing. Given 3 m off, where the scans do
        not match, the node stops sending map -> odom (it no longer knows where the robot is); given
        0.3 m and 0.15 rad off the truth, the robot is found there and map -> odom comes back within
        0.1 m of the truth."""
        pub = rospy.Publisher('/initialpose', PoseWithCovarianceStamped, queue_size=1, latch=True)
        time.sleep(1.0)  # the subscription connected

        def estimate(dx, dy, dyaw):
            p, q = self.truth.pose.pose.position, self.truth.pose.pose.orientation
            yaw = 2.0 * math.atan2(q.z, q.w) + dyaw
            msg = PoseWithCovarianceStamped()
            msg.header.frame_id, msg.header.stamp = 'map', rospy.Time.now()
            msg.pose.pose.position.x, msg.pose.pose.position.y = p.x + dx, p.y + dy
            msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
            pub.publish(msg)
            return rospy.get_time()

        given = estimate(3.0, 0.0, 0.0)
        time.sleep(3.0)  # wall: 10-30 s simulated
        self.assertEqual(self.pose_error(since=given + 1.0), math.inf, 'map -> odom still sent for a robot not found')
        given = estimate(0.3, -0.1, 0.15)
        self.wait('the robot placed again', lambda: self.pose_error(since=given) < 0.1, 60.0)

    def test_3_a_patrol_of_the_nine_points_twice_reaches_all_eighteen(self):
        patrol = subprocess.run(['roslaunch', 'mbot_slam_navigation', 'patrol.launch', 'rounds:=2', 'rest_time:=0.5'],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)
        out = patrol.stdout
        order = re.findall(r'Going to: (p\d)', out)
        self.assertEqual(order, ['p%d' % k for k in range(1, 10)] * 2, out[-3000:])
        summary = re.search(r'summary: (\d+) goals, (\d+) succeeded', out)
        self.assertIsNotNone(summary, out[-3000:])
        self.assertEqual((int(summary.group(1)), int(summary.group(2))), (18, 18), out[-3000:])
        self.assertLess(self.pose_error(), 0.1)
        self.assertEqual(self.contacts, [])


if __name__ == '__main__':
    rospy.init_node('slam_session_test')
    rostest.rosrun('mbot_slam_navigation', 'slam_session', SlamSessionTest)
