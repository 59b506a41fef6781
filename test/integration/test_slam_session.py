#!/usr/bin/env python3
"""A SLAM session saved halfway through the home's exploration, the node killed and started
again from it (slam_session.test): the session file is written and small, the restarted node serves
the saved map at once and finds the robot on it (within 0.1 m of the truth) by matching, and the
exploration, continued on it, finishes into one map with the walls where the world has them."""
import math
import os
import subprocess
import time
import unittest

import numpy as np
import rosnode
import rospy
import rostest
from nav_msgs.msg import OccupancyGrid, Odometry
from tf2_ros import Buffer, TransformListener

from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.srv import SerializePoseGraph, SerializePoseGraphResponse
from explore_result import wait_for_report

HALF_S = 90.0        # [s] simulated exploration before the session is saved (the home takes 180-260 s)
WAIT_S = 300.0       # [s] wall, for each step


def known_m2(msg):
    data = np.asarray(msg.data, np.int8)
    return float(np.count_nonzero(data >= 0)) * msg.info.resolution ** 2


class SlamSessionTest(unittest.TestCase):
    def setUp(self):
        self.map = None
        self.truth = None
        rospy.Subscriber('/map', OccupancyGrid, self.on_map, queue_size=1, buff_size=2 ** 24)
        rospy.Subscriber('/base_pose_ground_truth', Odometry, self.on_truth, queue_size=1)
        self.tf = Buffer(rospy.Duration(30.0))
        TransformListener(self.tf)
        self.restarted = None

    def tearDown(self):
        if self.restarted is not None and self.restarted.poll() is None:
            self.restarted.terminate()
            try:
                self.restarted.wait(20.0)
            except subprocess.TimeoutExpired:
                self.restarted.kill()

    def on_map(self, msg):
        self.map = msg

    def on_truth(self, msg):
        self.truth = msg

    def wait(self, what, ok, timeout=WAIT_S):
        end = time.monotonic() + timeout
        while not ok():
            if rospy.is_shutdown():
                self.fail('shut down waiting for %s' % what)
            if time.monotonic() > end:
                self.fail('%s: not within %.0f s (wall)' % (what, timeout))
            time.sleep(0.2)

    def pose_error(self):
        """[m] map -> base_footprint against the simulator's truth (the home's map frame is its
        world frame: the robot starts at the origin)."""
        try:
            t = self.tf.lookup_transform('map', 'base_footprint', rospy.Time(0), rospy.Duration(1.0))
        except Exception:
            return math.inf
        p = self.truth.pose.pose.position
        return math.hypot(t.transform.translation.x - p.x, t.transform.translation.y - p.y)

    def test_a_session_saved_and_continued_finishes_the_exploration(self):
        contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, contacts.append)
        session = rospy.get_param('~session')
        path = session + '.posegraph'
        if os.path.exists(path):
            os.remove(path)
        self.wait('half the exploration', lambda: self.map is not None and rospy.get_time() >= HALF_S)

        rospy.wait_for_service('/slam_gmapping/serialize_map', 30.0)
        save = rospy.ServiceProxy('/slam_gmapping/serialize_map', SerializePoseGraph)
        self.assertEqual(save(session).result, SerializePoseGraphResponse.RESULT_SUCCESS)
        self.assertTrue(os.path.isfile(path))
        size_mb = os.path.getsize(path) / 1e6
        self.assertLess(size_mb, 20.0)
        before = known_m2(self.map)

        rosnode.kill_nodes(['/slam_gmapping'])
        self.wait('slam_gmapping gone', lambda: not rosnode.rosnode_ping('/slam_gmapping', max_count=1), 30.0)
        self.map = None
        rospy.set_param('/slam_gmapping/session_file', session)
        env = dict(os.environ)
        started = time.monotonic()
        self.restarted = subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'slam_gmapping', '__name:=slam_gmapping',
                                           'scan:=/scan'], env=env)
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
        self.assertEqual(contacts, [])
        rospy.loginfo('continued exploration: %.0f s simulated, coverage %.1f%%, walls %.1f%% within 0.1 m',
                      r['exploration_time_s'], 100 * r['coverage_of_reachable_free'], 100 * r['walls_within_tolerance'])


if __name__ == '__main__':
    rospy.init_node('slam_session_test')
    rostest.rosrun('mbot_slam_navigation', 'slam_session', SlamSessionTest)
