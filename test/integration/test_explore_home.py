#!/usr/bin/env python3
"""explore in the home (explore_home.test): completion within 10 simulated minutes, at least 97% of
the reachable free space explored, the walls within 0.1 m of the world's, no collision; the report's
files are kept beside the test results (artifacts/explore_report)."""
import os
import unittest

import rospy
import rostest

from mbot_slam_navigation.msg import Contact
from explore_result import wait_for_report

LIMIT_S = 600.0  # [s] simulated, exploration until completion is announced


class ExploreHomeTest(unittest.TestCase):
    def test_exploration_finishes_and_maps_the_home(self):
        contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, contacts.append)
        r = wait_for_report('explore_report', first_timeout=60.0)
        report_dir = r['report_dir']
        self.assertEqual(r['outcome'], 'complete')
        self.assertLessEqual(r['exploration_time_s'], LIMIT_S)
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.97)
        self.assertGreaterEqual(r['walls_within_tolerance'], 0.99)
        self.assertEqual(r['collisions'], 0)
        self.assertEqual(contacts, [])
        for name in ('map.pgm', 'map.yaml', 'map.png', 'area.png'):
            self.assertTrue(os.path.isfile(os.path.join(report_dir, name)), name)
        self.assertGreater(r['distance_m'], 10.0)
        rospy.loginfo('exploration: %.0f s simulated (%.0f s wall), coverage %.1f%%, walls %.1f%% within 0.1 m',
                      r['exploration_time_s'], r['wall_time_s'], 100 * r['coverage_of_reachable_free'],
                      100 * r['walls_within_tolerance'])


if __name__ == '__main__':
    rospy.init_node('explore_home_test')
    rostest.rosrun('mbot_slam_navigation', 'explore_home', ExploreHomeTest)
