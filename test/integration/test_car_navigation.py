#!/usr/bin/env python3
"""The car tutorial as a user runs it (car_navigation.test): map_server + amcl_diff + move_base on
the saved map of wall.world. Every amcl_pose is compared with the simulator's ground truth at the
same simulated time. Tests run in order; each starts where the previous one left the car.
"""
import math
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import PoseArray, PoseWithCovarianceStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.nav.action_client import SimpleActionClient
from mbot_slam_navigation.transforms import yaw_to_quaternion
from pose_track import PoseTrack

# wall.world: three rooms side by side; the left and middle ones join at the top, the middle and
# right ones at the bottom. The car starts at the origin, in the middle room, facing +x.
GOALS = [(0.0, 3.4, math.pi / 2), (-3.2, -3.0, -math.pi / 2), (0.0, -3.4, 0.0)]
TRACK_TOL = 0.15   # [m] amcl's estimate against ground truth, all along the way
WRONG_START = (0.7, 0.5, 0.3)  # the initial pose a user gets wrong: 0.86 m and 0.3 rad off


class CarNavigationTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.track = PoseTrack('/amcl_pose')
        cls.contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, cls.contacts.append)
        cls.client = SimpleActionClient('move_base', MoveBaseAction)
        assert cls.client.wait_for_server(rospy.Duration(120.0)), 'no move_base action server'
        rospy.wait_for_message('/amcl_pose', PoseWithCovarianceStamped, timeout=60.0)
        cls.initial_pub = rospy.Publisher('/initialpose', PoseWithCovarianceStamped, queue_size=1, latch=True)

    def go(self, target, timeout=240.0):
        g = MoveBaseGoal()
        g.target_pose.header.frame_id = 'map'
        g.target_pose.header.stamp = rospy.Time.now()
        g.target_pose.pose.position.x, g.target_pose.pose.position.y = target[:2]
        o = g.target_pose.pose.orientation
        o.x, o.y, o.z, o.w = yaw_to_quaternion(target[2])
        self.client.send_goal(g)
        self.assertTrue(self.client.wait_for_result(rospy.Duration(timeout)), 'no result within %.0f s' % timeout)
        return self.client.get_state(), self.client.get_goal_status_text()

    def test_1_three_goals_with_amcl_tracking_ground_truth(self):
        t0 = rospy.get_time()
        for goal in GOALS:
            state, text = self.go(goal)
            self.assertEqual(state, GoalStatus.SUCCEEDED, 'goal %s: %s' % (goal, text))
            _, (x, y, _) = self.track.truth_at(rospy.get_time())
            self.assertLess(math.hypot(x - goal[0], y - goal[1]), 0.1 + TRACK_TOL, 'goal %s, truth (%.2f, %.2f)' % (goal, x, y))
        errors = self.track.errors_since(t0)
        self.assertGreater(len(errors), 40, 'amcl updated only %d times over three goals' % len(errors))
        worst = max(errors, key=lambda e: e[1])
        rospy.loginfo('amcl tracking: %d estimates, worst %.3f m at t=%.1f, mean %.3f m', len(errors), worst[1],
                      worst[0], sum(e[1] for e in errors) / len(errors))
        self.assertLess(worst[1], TRACK_TOL, 'amcl was %.3f m off ground truth at t=%.1f' % (worst[1], worst[0]))
        self.assertLess(max(e[2] for e in errors), 0.15)
        self.assertEqual([c for c in self.contacts if 'robot' in (c.model_a, c.model_b)], [], 'the car touched a wall')

    def test_2_wrong_initial_pose_within_1m_recovers(self):
        _, truth = self.track.truth_at(rospy.get_time())
        wrong = (truth[0] + WRONG_START[0], truth[1] + WRONG_START[1], truth[2] + WRONG_START[2])
        msg = PoseWithCovarianceStamped()
        msg.header.frame_id = 'map'
        msg.header.stamp = rospy.Time.now()
        msg.pose.pose.position.x, msg.pose.pose.position.y = wrong[:2]
        o = msg.pose.pose.orientation
        o.x, o.y, o.z, o.w = yaw_to_quaternion(wrong[2])
        msg.pose.covariance[0] = msg.pose.covariance[7] = 0.25     # rviz's 2D Pose Estimate
        msg.pose.covariance[35] = 0.06853891945200942
        t0 = rospy.get_time()
        self.initial_pub.publish(msg)
        rospy.sleep(1.0)
        first = self.track.errors_since(t0)
        self.assertTrue(first and first[0][1] > 0.4, 'the wrong pose was not taken: %s' % first[:1])
        # Drive on; the estimate must come back to the truth and stay there.
        state, text = self.go((0.0, 3.4, math.pi / 2))
        errors = self.track.errors_since(t0)
        settled = [e for e in errors if e[0] > errors[0][0] + 0.6 * (errors[-1][0] - errors[0][0])]
        rospy.loginfo('wrong start: first error %.2f m, last %.3f m, %d estimates', errors[0][1], errors[-1][1],
                      len(errors))
        self.assertTrue(settled, 'no estimates while driving')
        self.assertLess(max(e[1] for e in settled), TRACK_TOL, 'amcl did not recover: %s' % settled[-3:])
        self.assertEqual(state, GoalStatus.SUCCEEDED, text)

    def test_3_amcl_publishes_particles_and_transform(self):
        cloud = rospy.wait_for_message('/particlecloud', PoseArray, timeout=10.0)
        self.assertEqual(cloud.header.frame_id, 'map')
        self.assertGreaterEqual(len(cloud.poses), 500)   # min_particles of amcl_diff.launch


if __name__ == '__main__':
    rospy.init_node('test_car_navigation')
    rostest.rosrun('mbot_slam_navigation', 'car_navigation', CarNavigationTest)
