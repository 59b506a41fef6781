"""What the navigation rostests share: move_base sent to the tutorial's nine points in turn
(random_navigation.py's table), each checked against the simulator's ground truth."""
import math

import rospy
from actionlib_msgs.msg import GoalStatus
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

from mbot_slam_navigation.nav.action_client import SimpleActionClient
from mbot_slam_navigation.nav.random_navigation import tutorial_locations


def reach_tutorial_points(test, truth, goal_timeout: float, xy_tol: float) -> None:
    """Fails `test` (a unittest.TestCase) at the first point move_base does not reach within
    goal_timeout [s, simulated] or where the robot's true position (truth(): a geometry_msgs/Point)
    lies farther than xy_tol [m] from it."""
    client = SimpleActionClient('move_base', MoveBaseAction)
    test.assertTrue(client.wait_for_server(rospy.Duration(30.0)), 'no move_base action server')
    for loc in tutorial_locations():
        goal = MoveBaseGoal()
        goal.target_pose.header.frame_id = 'map'
        goal.target_pose.header.stamp = rospy.Time.now()
        goal.target_pose.pose.position.x, goal.target_pose.pose.position.y = loc.x, loc.y
        (goal.target_pose.pose.orientation.x, goal.target_pose.pose.orientation.y,
         goal.target_pose.pose.orientation.z, goal.target_pose.pose.orientation.w) = loc.orientation
        client.send_goal(goal)
        finished = client.wait_for_result(rospy.Duration(goal_timeout))
        state = client.get_state()
        test.assertTrue(finished and state == GoalStatus.SUCCEEDED,
                        '%s (%s, %.2f, %.2f): %s' % (loc.name, loc.room, loc.x, loc.y,
                                                    client.get_goal_status_text() or 'no result in time'))
        p = truth()
        test.assertLess(math.hypot(p.x - loc.x, p.y - loc.y), xy_tol, loc.name)
