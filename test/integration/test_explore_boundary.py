#!/usr/bin/env python3
"""Exploring inside a boundary (explore_boundary.test): the exploration completes, the reachable
floor inside the boundary is mapped, the robot never leaves it (its ground-truth centre stays within
0.3 m of it), and the report counts the frontier it left outside."""
import unittest

import numpy as np
import rospy
import rostest
from nav_msgs.msg import Odometry

from explore_result import wait_for_report

MARGIN = 0.3  # [m] a goal inside, near the boundary, and the way to it


class ExploreBoundaryTest(unittest.TestCase):
    def test_the_exploration_stays_inside_its_boundary(self):
        path = []
        rospy.Subscriber('/base_pose_ground_truth', Odometry,
                         lambda m: path.append((m.pose.pose.position.x, m.pose.pose.position.y)), queue_size=50)
        r = wait_for_report('explore_boundary_report', first_timeout=60.0)
        self.assertEqual(r['outcome'], 'complete')
        polygon = np.array(r['boundary'])
        lo, hi = polygon.min(axis=0) - MARGIN, polygon.max(axis=0) + MARGIN  # the boundary is a rectangle
        p = np.array(path)
        outside = p[np.any((p < lo) | (p > hi), axis=1)]
        self.assertEqual(len(outside), 0, 'the robot left the boundary at %s' % outside[:5].tolist())
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.95)  # inside the boundary
        self.assertGreater(r['frontier_outside_boundary_m'], 0.5)
        for room in ('living room', 'kitchen', 'dining room', 'bathroom'):
            self.assertGreaterEqual(r['room_coverage'][room], 0.9, room)
        self.assertEqual(r['collisions'], 0)
        rospy.loginfo('boundary: complete after %.0f s simulated, coverage inside %.1f%%, %.1f m of frontier left '
                      'outside; rooms %s', r['exploration_time_s'], 100 * r['coverage_of_reachable_free'],
                      r['frontier_outside_boundary_m'], r['room_coverage'])


if __name__ == '__main__':
    rospy.init_node('explore_boundary_test')
    rostest.rosrun('mbot_slam_navigation', 'explore_boundary', ExploreBoundaryTest)
