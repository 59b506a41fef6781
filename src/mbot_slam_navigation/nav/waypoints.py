"""follow_waypoints: an action server that sends move_base to poses in order (Nav2's FollowWaypoints
action, with rounds and a dwell time), and the next point drawn in rviz.

Action `follow_waypoints` (mbot_slam_navigation/FollowWaypointsAction): goal poses (each in its own
frame), rounds (0 or 1: once), dwell_s [s]. A pose move_base cannot reach is skipped with move_base's
reason (result.missed_waypoints / missed_reasons, Nav2's field and ours); move_base's faults are seen
through as random_navigation.py does (GoalSender.pursue). Feedback after every pose: current_waypoint,
round, reached, missed, distance_m. Cancelling the action cancels move_base's goal and stops the
robot. The tutorial-style lines (success so far, running time, distance) go to the log.

Topics: `~next_waypoint` (visualization_msgs/Marker, latched: an arrow at the pose being driven to,
deleted when the action ends). Parameters: goal_timeout (300 s per pose), server_timeout (60 s for
move_base), base_frame (base_footprint). Distances are straight lines between where the robot stood
after each pose (tf, in the pose's frame), as the tutorial counts.
"""
import math
import sys
from typing import List, Optional, Tuple

import actionlib
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, Twist
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from visualization_msgs.msg import Marker

from mbot_slam_navigation.lazy_tf import LazyTransformBuffer
from mbot_slam_navigation.msg import FollowWaypointsAction, FollowWaypointsFeedback, FollowWaypointsResult
from mbot_slam_navigation.nav.action_client import SimpleActionClient
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.nav.random_navigation import GoalSender, Location, Tally, next_marker
from mbot_slam_navigation.transforms import check_planar_quaternion

DWELL_STEP = 0.1  # [s] a dwell is cut short this soon after a cancel


def read_parameters(r: ParamReader) -> dict:
    return {
        'goal_timeout': r.number('goal_timeout', 300.0, '[s] a pose not reached in this time is skipped',
                                 positive=True),
        'server_timeout': r.number('server_timeout', 60.0, '[s] wait for the move_base action server', positive=True),
        'base_frame': r.frame('base_frame', 'base_footprint', "the robot's base frame (distance driven, from tf)"),
    }


class WaypointFollower(GoalSender):
    log_name = 'follow_waypoints'

    def __init__(self):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        c = read_parameters(r)
        r.report_unknown()
        self.goal_timeout, self.server_timeout, self.base_frame = c['goal_timeout'], c['server_timeout'], c['base_frame']
        self.move_base = SimpleActionClient('move_base', MoveBaseAction)
        self.tf = LazyTransformBuffer()
        self.cmd_vel_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self.marker_pub = rospy.Publisher('~next_waypoint', Marker, queue_size=1, latch=True)
        self.poses: List[PoseStamped] = []
        self.server = actionlib.SimpleActionServer('follow_waypoints', FollowWaypointsAction, self.execute,
                                                   auto_start=False)
        self.server.start()
        rospy.loginfo('follow_waypoints: ready on %s', rospy.resolve_name('follow_waypoints'))

    def stop_requested(self) -> bool:
        return self.server.is_preempt_requested() or rospy.is_shutdown()

    def goal(self, loc: Location) -> MoveBaseGoal:
        g = MoveBaseGoal()
        g.target_pose = self.poses[int(loc.name.split()[-1])]
        g.target_pose.header.stamp = rospy.Time.now()
        return g

    def position(self, frame: str) -> Optional[Tuple[float, float]]:
        try:
            t = self.tf.lookup_transform(frame, self.base_frame, rospy.Time(0), rospy.Duration(0.5))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException):
            return None
        return t.transform.translation.x, t.transform.translation.y

    def check(self, poses: List[PoseStamped]) -> str:
        """Why the goal's poses cannot be used, or ''."""
        if not poses:
            return 'no poses'
        for i, p in enumerate(poses):
            q = p.pose.orientation
            yaw, note = check_planar_quaternion((q.x, q.y, q.z, q.w), 'poses[%d].orientation' % i)
            if yaw is None:
                return note
            if not p.header.frame_id:
                return 'poses[%d] has an empty frame_id' % i
            if not (math.isfinite(p.pose.position.x) and math.isfinite(p.pose.position.y)):
                return 'poses[%d] is not finite' % i
        return ''

    def dwell(self, seconds: float) -> bool:
        """Stands `seconds` [s, ROS time]; False when cancelled meanwhile."""
        end = rospy.Time.now() + rospy.Duration(seconds)
        while rospy.Time.now() < end:
            if self.stop_requested():
                return False
            try:
                rospy.sleep(DWELL_STEP)
            except (rospy.ROSTimeMovedBackwardsException, rospy.ROSInterruptException):
                return not rospy.is_shutdown()
        return True

    def execute(self, goal) -> None:
        why = self.check(list(goal.poses))
        if why:
            rospy.logwarn('follow_waypoints: goal rejected: %s', why)
            self.server.set_aborted(FollowWaypointsResult(), 'follow_waypoints: ' + why)
            return
        if not self.move_base.wait_for_server(rospy.Duration(self.server_timeout)):
            self.server.set_aborted(FollowWaypointsResult(), 'no move_base action server on %s after %g s'
                                    % (rospy.resolve_name('move_base'), self.server_timeout))
            return
        self.poses = list(goal.poses)
        rounds = max(1, goal.rounds)
        start = rospy.Time.now()
        result, feedback, tally = FollowWaypointsResult(), FollowWaypointsFeedback(), Tally()
        driven = 0.0
        last = self.position(self.poses[0].header.frame_id)
        rospy.loginfo('follow_waypoints: %d poses, %d round%s, dwell %.1f s', len(self.poses), rounds,
                      '' if rounds == 1 else 's', goal.dwell_s)
        for rnd in range(1, rounds + 1):
            for i, pose in enumerate(self.poses):
                feedback.current_waypoint, feedback.round = i, rnd
                self.server.publish_feedback(feedback)
                self.marker_pub.publish(next_marker(pose, 'waypoint %d, round %d of %d' % (i, rnd, rounds)))
                p = pose.pose.position
                rospy.loginfo('follow_waypoints: going to waypoint %d (%.2f, %.2f) in %s', i, p.x, p.y,
                              pose.header.frame_id)
                state = self.pursue(Location('waypoint %d' % i, '', p.x, p.y, (0.0, 0.0, 0.0, 1.0)))
                if state is None or state == 'PREEMPTED' or self.stop_requested():
                    self.finish(result, tally, start, feedback)
                    self.server.set_preempted(result, 'cancelled at waypoint %d, round %d' % (i, rnd))
                    return
                here = self.position(pose.header.frame_id)
                step = math.hypot(here[0] - last[0], here[1] - last[1]) if here and last else 0.0
                last = here or last
                driven += step
                tally.record(str(i), state, step)
                tally.distance = driven  # the log's distance: all the way, reached or not
                if state == 'SUCCEEDED':
                    feedback.reached += 1
                else:
                    reason = self.move_base.get_goal_status_text() or state
                    rospy.logwarn('follow_waypoints: waypoint %d skipped (%s): %s', i, state, reason)
                    result.missed_waypoints.append(i)
                    result.missed_reasons.append(reason)
                    feedback.missed += 1
                feedback.distance_m = driven
                rospy.loginfo(tally.success_line())
                rospy.loginfo(tally.time_line((rospy.Time.now() - start).to_sec()))
                if state == 'SUCCEEDED' and goal.dwell_s > 0 and not self.dwell(goal.dwell_s):
                    self.finish(result, tally, start, feedback)
                    self.server.set_preempted(result, 'cancelled while standing at waypoint %d' % i)
                    return
        self.finish(result, tally, start, feedback)
        text = '%d of %d reached' % (result.reached, rounds * len(self.poses))
        rospy.loginfo('follow_waypoints: done: %s%s', text, ', missed %s' % result.missed_waypoints
                      if result.missed_waypoints else '')
        self.server.set_succeeded(result, text)

    def finish(self, result, tally: Tally, start, feedback) -> None:
        result.reached = feedback.reached
        result.distance_m = tally.distance
        result.time_s = (rospy.Time.now() - start).to_sec()
        self.cmd_vel_pub.publish(Twist())
        self.marker_pub.publish(Marker(ns="next_point", id=0, action=Marker.DELETE))


def main() -> None:
    rospy.init_node('follow_waypoints')
    try:
        WaypointFollower()
    except ParamError as e:
        rospy.logfatal('follow_waypoints: %s', e)
        sys.exit(2)
    rospy.spin()
