#!/usr/bin/env python3
"""team_timeout.test: explore_team ends a team whose explorer does not end by itself, at its
timeout, with a report that names the robot and why."""
import os
import unittest

import rospy
import rostest
from std_msgs.msg import Bool

from explore_result import wait_for_report

TIMEOUT_S = 20.0  # [s] simulated: explore_team/timeout in team_timeout.test


class TeamTimeoutTest(unittest.TestCase):
    def test_the_team_report_comes_at_the_timeout_with_the_late_robot_named(self):
        r = wait_for_report('team_timeout_report', first_timeout=120.0, end_timeout=300.0, node='/explore_team')
        self.assertEqual(r['outcome'], 'timeout', r)
        robot = r['per_robot']['robot1']
        self.assertEqual(robot['outcome'], 'timeout', r)
        self.assertIn('did not end within 20 s simulated', robot['why'])
        self.assertGreaterEqual(robot['exploration_time_s'], TIMEOUT_S)
        self.assertLess(robot['exploration_time_s'], TIMEOUT_S + 30.0)  # polled at 2 Hz of wall time
        # the explorer itself is still exploring: it was not the one that ended the run
        explorer_done = rospy.wait_for_message('/robot1/explore/complete', Bool, timeout=10.0)
        self.assertFalse(explorer_done.data)
        for name in ('map.pgm', 'map.yaml', 'map.png', 'area.png'):
            self.assertTrue(os.path.isfile(os.path.join(r['report_dir'], name)), name)


if __name__ == '__main__':
    rospy.init_node('team_timeout_test')
    rostest.rosrun('mbot_slam_navigation', 'team_timeout', TeamTimeoutTest)
