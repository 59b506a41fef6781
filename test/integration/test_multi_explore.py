#!/usr/bin/env python3
"""multi_explore.test: two robots explore the home together; the team's report says complete, the
merged map covers at least 97% of the reachable free space with 99% of its walls within 0.1 m of the
world's, no robot touched anything, both robots drove, and the map and picture are written."""
import os
import unittest

import rospy
import rostest

from mbot_slam_navigation.msg import Contact
from explore_result import wait_for_report

LIMIT_S = 900.0  # [s] simulated: a generous bound; the figure to beat is one robot's (bench_explore.py)


class MultiExploreTest(unittest.TestCase):
    def test_two_robots_map_the_home_together(self):
        contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, contacts.append)
        r = wait_for_report('multi_explore_report', first_timeout=120.0, end_timeout=1500.0, node='/explore_team')
        self.assertEqual(r['outcome'], 'complete', r)
        self.assertEqual(r['robots'], 2)
        self.assertLessEqual(r['exploration_time_s'], LIMIT_S)
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.97)
        self.assertGreaterEqual(r['walls_within_tolerance'], 0.99)
        self.assertEqual(r['collisions'], 0)
        self.assertEqual([c for c in contacts if c.robot_at_fault], [])
        for name in ('robot1', 'robot2'):
            self.assertEqual(r['per_robot'][name]['outcome'], 'complete')
            self.assertGreater(r['per_robot'][name]['distance_m'], 3.0, name)  # each did its share
        for name in ('map.pgm', 'map.yaml', 'map.png', 'area.png'):
            self.assertTrue(os.path.isfile(os.path.join(r['report_dir'], name)), name)
        rospy.loginfo('team exploration: %.0f s simulated (%.0f s wall), coverage %.1f%%, walls %.1f%%, distances %s',
                      r['exploration_time_s'], r['wall_time_s'], 100 * r['coverage_of_reachable_free'],
                      100 * r['walls_within_tolerance'], {k: v['distance_m'] for k, v in r['per_robot'].items()})


if __name__ == '__main__':
    rospy.init_node('multi_explore_test')
    rostest.rosrun('mbot_slam_navigation', 'multi_explore', MultiExploreTest)
