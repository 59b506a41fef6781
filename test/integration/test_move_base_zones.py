#!/usr/bin/env python3
"""move_base with keep-out and speed zones (move_base_zones.test), checked against the simulator's
ground truth. The robot starts at the world origin in the living room, which is a 30% speed zone;
the room north of it at x -5.4..-2.0, y 0.9..3.6 is keep-out. Tests run in order."""
import math
import threading
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan, GetPlanRequest
from geometry_msgs.msg import PoseStamped

from mbot_slam_navigation.nav.action_client import SimpleActionClient
from move_base_msgs.msg import MoveBaseAction

from test_move_base_home import goal_msg

MAX_VEL_X = 0.3                               # config/base_local_planner_params.yaml
SPEED_ZONE = (-5.4, -6.0, 1.2, 0.9)           # maps/home_speed.yaml: the living room, 30%
KEEPOUT = (-5.4, 0.9, -2.0, 3.6)              # maps/home_keepout.yaml
ROBOT_RADIUS = 0.2


def inside(box, x, y, margin=0.0):
    return box[0] + margin <= x <= box[2] - margin and box[1] + margin <= y <= box[3] - margin


class MoveBaseZonesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = SimpleActionClient('move_base', MoveBaseAction)
        assert cls.client.wait_for_server(rospy.Duration(120.0)), 'no move_base action server'
        rospy.wait_for_message('/move_base/global_costmap/costmap', rospy.AnyMsg, timeout=60.0)
        cls.lock = threading.Lock()
        cls.samples = []  # (x, y, speed [m/s]) from the ground truth
        rospy.Subscriber('/base_pose_ground_truth', Odometry, cls.on_truth, queue_size=100)

    @classmethod
    def on_truth(cls, m):
        t = m.twist.twist.linear
        with cls.lock:
            cls.samples.append((m.pose.pose.position.x, m.pose.pose.position.y, math.hypot(t.x, t.y)))

    def go(self, x, y, yaw, timeout=150.0):
        self.client.send_goal(goal_msg(x, y, yaw))
        self.assertTrue(self.client.wait_for_result(rospy.Duration(timeout)), 'no result within %.0f s' % timeout)
        return self.client.get_state(), self.client.get_goal_status_text()

    def test_1_a_goal_in_a_keepout_zone_is_aborted_at_once_naming_it(self):
        t0 = rospy.Time.now()
        state, text = self.go(-3.7, 2.3, 0.0, timeout=10.0)
        took = (rospy.Time.now() - t0).to_sec()
        self.assertEqual(state, GoalStatus.ABORTED, text)
        self.assertIn('keep-out zone #1 at (-3.7, 2.3) (filter keepout_filter)', text)
        self.assertLess(took, 1.0)
        plan = rospy.ServiceProxy('/move_base/make_plan', GetPlan)
        req = GetPlanRequest()
        req.goal = PoseStamped()
        req.goal.header.frame_id = 'map'
        req.goal.pose.position.x, req.goal.pose.position.y = -3.7, 2.3
        req.goal.pose.orientation.w = 1.0
        self.assertEqual(len(plan(req).plan.poses), 0)
        rospy.loginfo('keep-out: goal aborted after %.2f s (simulated): %s', took, text)

    def test_2_the_robot_keeps_to_30_percent_in_the_speed_zone_and_not_outside(self):
        with self.lock:
            del self.samples[:]
        for x, y, yaw in ((-2.5, -3.0, math.pi), (3.0, -4.8, 0.0)):  # across the living room, then the kitchen
            state, text = self.go(x, y, yaw)
            self.assertEqual(state, GoalStatus.SUCCEEDED, text)
        with self.lock:
            samples = list(self.samples)
        # where the whole footprint is in the zone, and where none of it is
        zone = [v for x, y, v in samples if inside(SPEED_ZONE, x, y, ROBOT_RADIUS)]
        free = [v for x, y, v in samples if not inside(SPEED_ZONE, x, y, -ROBOT_RADIUS - 0.05)]
        self.assertGreater(len(zone), 100)
        self.assertGreater(len(free), 20)
        self.assertLessEqual(max(zone), 0.3 * MAX_VEL_X + 0.02)
        self.assertGreater(max(free), 0.3 * MAX_VEL_X + 0.05)  # the limit holds in the zone only
        for x, y, _ in samples:
            self.assertFalse(inside(KEEPOUT, x, y, -ROBOT_RADIUS), 'in the keep-out zone at (%.2f, %.2f)' % (x, y))
        rospy.loginfo('speed zone: fastest %.3f m/s inside (limit %.3f), %.3f m/s outside', max(zone),
                      0.3 * MAX_VEL_X, max(free))


if __name__ == '__main__':
    rospy.init_node('move_base_zones_test')
    rostest.rosrun('mbot_slam_navigation', 'move_base_zones', MoveBaseZonesTest)
