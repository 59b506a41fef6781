#!/usr/bin/env python3
"""follow_waypoints as a user drives it (follow_waypoints.test): poses visited in order, round after
round, a pose inside a wall skipped with move_base's reason, the next pose drawn in rviz, feedback
after every pose; a cancel stops the robot. Checked against the simulator's ground truth."""
import math
import threading
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from nav_msgs.msg import Odometry
from visualization_msgs.msg import Marker

from mbot_slam_navigation.msg import FollowWaypointsAction, FollowWaypointsGoal
from mbot_slam_navigation.nav.action_client import SimpleActionClient

from test_move_base_home import goal_msg

POSES = [(-1.5, -2.0, -math.pi / 2), (-0.5, -3.5, 0.0), (-2.5, -3.0, math.pi), (-3.8, 0.9, 0.0)]  # the last in a wall
REACHABLE = 3


def pose_stamped(x, y, yaw):
    return goal_msg(x, y, yaw).target_pose  # in map


class FollowWaypointsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = SimpleActionClient('follow_waypoints', FollowWaypointsAction)
        assert cls.client.wait_for_server(rospy.Duration(120.0)), 'no follow_waypoints action server'
        rospy.wait_for_message('/move_base/global_costmap/costmap', rospy.AnyMsg, timeout=60.0)
        cls.lock = threading.Lock()
        cls.truth, cls.markers, cls.feedback = [], [], []
        rospy.Subscriber('/base_pose_ground_truth', Odometry, cls.on_truth, queue_size=50)
        rospy.Subscriber('/follow_waypoints/next_waypoint', Marker, cls.markers.append)

    @classmethod
    def on_truth(cls, m):
        with cls.lock:
            cls.truth.append((m.header.stamp.to_sec(), m.pose.pose.position.x, m.pose.pose.position.y,
                              math.hypot(m.twist.twist.linear.x, m.twist.twist.angular.z)))

    def test_1_two_rounds_in_order_with_a_pose_in_a_wall_skipped(self):
        goal = FollowWaypointsGoal(poses=[pose_stamped(*p) for p in POSES], rounds=2, dwell_s=1.0)
        self.client.send_goal(goal, feedback_cb=self.feedback.append)
        self.assertTrue(self.client.wait_for_result(rospy.Duration(400.0)), 'no result in 400 s')
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED, self.client.get_goal_status_text())
        r = self.client.get_result()
        self.assertEqual(r.reached, 2 * REACHABLE)
        self.assertEqual(list(r.missed_waypoints), [3, 3])
        self.assertTrue(all('goal occupied' in why or 'Failed to find a valid plan' in why for why in r.missed_reasons),
                        r.missed_reasons)
        self.assertGreater(r.distance_m, 4.0)
        # the feedback names each pose in order, round after round
        order = [(f.round, f.current_waypoint) for f in self.feedback]
        firsts = [o for i, o in enumerate(order) if i == 0 or o != order[i - 1]]
        self.assertEqual(firsts, [(rnd, i) for rnd in (1, 2) for i in range(len(POSES))])
        self.assertEqual(self.feedback[-1].reached, 2 * REACHABLE)
        # the ground truth passed within 0.2 m of each reachable pose, in order, twice
        with self.lock:
            track = list(self.truth)
        visits, k = [], 0
        for _, x, y, _ in track:
            px, py, _ = POSES[k % REACHABLE]
            if math.hypot(x - px, y - py) < 0.2:
                visits.append(k % REACHABLE)
                k += 1
        self.assertGreaterEqual(k, 2 * REACHABLE, 'visited in order: %s' % visits)
        # the next pose was drawn, then deleted at the end
        self.assertTrue(any(m.action == Marker.ADD and 'waypoint 2, round 2' in m.text for m in self.markers))
        rospy.sleep(0.5)
        self.assertEqual(self.markers[-1].action, Marker.DELETE)

    def test_2_a_cancel_stops_the_robot(self):
        goal = FollowWaypointsGoal(poses=[pose_stamped(-4.2, -4.5, math.pi)], rounds=1, dwell_s=0.0)
        self.client.send_goal(goal)
        rospy.sleep(4.0)
        self.client.cancel_goal()
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10.0)))
        self.assertEqual(self.client.get_state(), GoalStatus.PREEMPTED)
        t_cancel = rospy.Time.now().to_sec()
        rospy.sleep(3.0)
        with self.lock:
            after = [v for t, _, _, v in self.truth if t > t_cancel + 1.0]
        self.assertTrue(after)
        self.assertLess(max(after), 0.02, 'still moving 1 s after the cancel')


if __name__ == '__main__':
    rospy.init_node('follow_waypoints_test')
    rostest.rosrun('mbot_slam_navigation', 'follow_waypoints_test', FollowWaypointsTest)
