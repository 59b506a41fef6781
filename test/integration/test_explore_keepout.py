#!/usr/bin/env python3
"""Exploring with a keep-out zone (explore_keepout.test): the robot's ground-truth footprint never
covers a cell of the zone, the exploration completes, the frontier into the zone is reported as
excluded, and the reachable floor outside the zone is mapped."""
import os
import unittest

import numpy as np
import rospy
import rostest
from nav_msgs.msg import Odometry

from mbot_slam_navigation.maps.map_io import load_map
from mbot_slam_navigation.nav.frontiers import Grid

from explore_result import wait_for_report

MASK = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'maps', 'home_keepout.yaml')
ROBOT_RADIUS = 0.2  # [m] the mbot's (config/mbot/costmap_common_params.yaml)


class ExploreKeepoutTest(unittest.TestCase):
    def test_the_robot_stays_out_of_the_zone_and_the_exploration_completes(self):
        m = load_map(MASK)
        mask = Grid(m.data, m.resolution, m.origin[:2])
        rows, cols = np.nonzero(mask.data >= 100)
        zx, zy = mask.centre_of(rows, cols)
        half = mask.resolution / 2
        path = []
        rospy.Subscriber('/base_pose_ground_truth', Odometry,
                         lambda msg: path.append((msg.pose.pose.position.x, msg.pose.pose.position.y)), queue_size=50)
        r = wait_for_report('explore_keepout_report', first_timeout=60.0)
        self.assertEqual(r['outcome'], 'complete')
        p = np.array(path)
        self.assertGreater(len(p), 100)
        near = np.all((p > np.array([zx.min(), zy.min()]) - 1.0) & (p < np.array([zx.max(), zy.max()]) + 1.0), axis=1)
        p = p[near] if near.any() else p[:1]
        # a zone cell overlaps the footprint's disc when the disc reaches the nearest point of the cell
        dx = np.maximum(np.abs(p[:, None, 0] - zx[None, :]) - half, 0.0)
        dy = np.maximum(np.abs(p[:, None, 1] - zy[None, :]) - half, 0.0)
        inside = np.hypot(dx, dy) < ROBOT_RADIUS
        entered = np.flatnonzero(inside.any(axis=1))
        self.assertEqual(len(entered), 0, 'the footprint covered %d zone cells, first at %s'
                         % (int(inside.any(axis=0).sum()), p[entered[:3]].tolist()))
        nearest = float(np.min(np.hypot(dx, dy)))
        self.assertAlmostEqual(r['keepout_m2'], len(zx) * mask.resolution ** 2, delta=0.01)
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.95)  # of the floor outside the zone
        self.assertEqual(r['collisions'], 0)
        for g in r['given_up']:  # nothing left behind the zone as unreachable: it is excluded
            self.assertFalse(-5.4 <= g['x'] <= -2.0 and 0.9 <= g['y'] <= 3.6, g)
        rospy.loginfo('keepout: complete after %.0f s simulated, coverage outside the zone %.1f%%, nearest approach '
                      'of the footprint to the zone %.2f m, %.1f m of frontier excluded at the end',
                      r['exploration_time_s'], 100 * r['coverage_of_reachable_free'], nearest, r['frontier_in_keepout_m'])


if __name__ == '__main__':
    rospy.init_node('explore_keepout_test')
    rostest.rosrun('mbot_slam_navigation', 'explore_keepout', ExploreKeepoutTest)
