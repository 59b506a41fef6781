#!/usr/bin/env python3
"""How an exploration ends, as a user sees it in the report (explore_gap/boxed/timeout.test).

Private parameters of this test node: outcome (expected), max_exploration_s (simulated, the latest
the outcome may be decided), given_up_x_min (a frontier given up must lie east of this x [m], or
'' for none required)."""
import os
import unittest

import rospy
import rostest

from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.srv import GetModelState
from explore_result import wait_for_report


class ExploreOutcomeTest(unittest.TestCase):
    def test_the_exploration_ends_with_the_expected_outcome_and_a_report(self):
        expected = rospy.get_param('~outcome')
        limit = float(rospy.get_param('~max_exploration_s'))
        given_up_x_min = rospy.get_param('~given_up_x_min', '')
        contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, contacts.append)
        r = wait_for_report('explore_%s_report' % expected, end_timeout=900.0)
        report_dir = r['report_dir']
        self.assertEqual(r['outcome'], expected, r)
        self.assertLessEqual(r['exploration_time_s'], limit)
        self.assertEqual(r['collisions'], 0)
        self.assertEqual(contacts, [])
        for name in ('map.pgm', 'map.yaml', 'map.png', 'area.png'):
            self.assertTrue(os.path.isfile(os.path.join(report_dir, name)), name)
        if given_up_x_min != '':
            behind = [g for g in r['given_up'] if g['x'] > float(given_up_x_min)]
            self.assertTrue(behind, 'no frontier beyond x=%s given up: %s' % (given_up_x_min, r['given_up']))
            self.assertTrue(all(g['why'] for g in behind))
        if expected == 'stuck':
            # the robot stands still after the end (no command keeps it going)
            rospy.wait_for_service('/gazebo/get_model_state', timeout=10.0)
            state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)
            p0 = state(model_name='robot').pose.position
            rospy.sleep(3.0)
            p1 = state(model_name='robot').pose.position
            self.assertLess(abs(p1.x - p0.x) + abs(p1.y - p0.y), 0.01)


if __name__ == '__main__':
    rospy.init_node('explore_outcome_test')
    rostest.rosrun('mbot_slam_navigation', 'explore_outcome', ExploreOutcomeTest)
