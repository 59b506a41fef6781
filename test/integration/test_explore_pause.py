#!/usr/bin/env python3
"""explore/pause and explore/resume (explore_pause.test): paused 40 s into the home's exploration,
the robot stands within 1 s simulated and move_base gets no goal for the 20 s of the pause; resumed,
the exploration completes, and its report counts the pause (paused_s) apart from max_duration."""
import math
import time
import unittest

import rospy
import rostest
from move_base_msgs.msg import MoveBaseActionGoal
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger

from explore_result import wait_for_report

PAUSE_AT_S = 40.0   # [s] simulated
PAUSE_FOR_S = 20.0  # [s] simulated
STAND_S = 1.0       # [s] simulated: the robot stands within this of the pause
STILL = 0.02        # [m/s]


class ExplorePauseTest(unittest.TestCase):
    def test_a_paused_exploration_stands_and_resumed_completes(self):
        goals, speeds = [], []
        rospy.Subscriber('/move_base/goal', MoveBaseActionGoal, lambda m: goals.append(rospy.get_time()))
        rospy.Subscriber('/base_pose_ground_truth', Odometry, lambda m: speeds.append(
            (m.header.stamp.to_sec(), math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y))), queue_size=50)
        for name in ('/explore/pause', '/explore/resume'):
            rospy.wait_for_service(name, 120.0)
        pause = rospy.ServiceProxy('/explore/pause', Trigger)
        resume = rospy.ServiceProxy('/explore/resume', Trigger)
        end = time.monotonic() + 300.0
        while rospy.get_time() < PAUSE_AT_S:
            self.assertLess(time.monotonic(), end, 'the simulation did not reach %.0f s' % PAUSE_AT_S)
            time.sleep(0.1)
        self.assertTrue(goals, 'exploring: goals went to move_base before the pause')
        paused_at = rospy.get_time()
        self.assertIn('pausing', pause().message)
        self.assertIn('already paused', pause().message)
        while rospy.get_time() < paused_at + PAUSE_FOR_S:
            time.sleep(0.1)
        resume_at = rospy.get_time()
        self.assertIn('resuming', resume().message)
        during = [t for t in goals if paused_at + 0.5 < t < resume_at]
        self.assertEqual(during, [], 'goals sent while paused')
        moving = [(t, v) for t, v in speeds if paused_at + STAND_S < t < resume_at and v > STILL]
        self.assertEqual(moving, [], 'the robot moved while paused')
        r = wait_for_report('explore_pause_report', first_timeout=60.0)
        self.assertEqual(r['outcome'], 'complete')
        self.assertAlmostEqual(r['paused_s'], resume_at - paused_at, delta=1.0)
        self.assertGreaterEqual(r['coverage_of_reachable_free'], 0.97)
        self.assertTrue([t for t in goals if t > resume_at], 'goals after resuming')
        rospy.loginfo('paused %.1f s at %.0f s; completed after %.0f s simulated (paused_s %.1f), coverage %.1f%%',
                      resume_at - paused_at, paused_at, r['exploration_time_s'], r['paused_s'],
                      100 * r['coverage_of_reachable_free'])


if __name__ == '__main__':
    rospy.init_node('explore_pause_test')
    rostest.rosrun('mbot_slam_navigation', 'explore_pause', ExplorePauseTest)
