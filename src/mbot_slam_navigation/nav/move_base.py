"""The move_base node: actionlib server, planning / controlling / clearing states, recoveries.

Interfaces as ROS's move_base: action ``move_base`` (move_base_msgs/MoveBaseAction),
``move_base_simple/goal``, ``cmd_vel``, ``odom`` (for the robot's velocity), services ``~make_plan``
(nav_msgs/GetPlan) and ``~clear_costmaps`` (std_srvs/Empty); costmaps under ``~global_costmap`` and
``~local_costmap``; plans on ``~NavfnROS/plan`` (and ``~plan``), ``~TrajectoryPlannerROS/local_plan``
and ``~TrajectoryPlannerROS/global_plan``; the goal in use on ``~current_goal``.

Differences from ROS, on purpose: a failed replan while moving stops the robot (ROS keeps
following the old plan, possibly through a new obstacle); oscillation detection is on by default;
``~make_plan`` answers while a goal is active; a back-up recovery is among the defaults; every
abort says why.
"""
import math
import threading
from typing import Any, Dict, List, Optional, Tuple

import actionlib
import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, Twist
from move_base_msgs.msg import MoveBaseAction, MoveBaseActionGoal, MoveBaseFeedback, MoveBaseResult
from nav_msgs.msg import Odometry, Path
from nav_msgs.srv import GetPlan, GetPlanResponse
from std_msgs.msg import Header
from std_srvs.srv import Empty, EmptyResponse

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.costmap_ros import CostmapROS
from mbot_slam_navigation.nav.params import ParamError, ParamReader, nearest_key
from mbot_slam_navigation.nav.trajectory_planner import TrajectoryController, local_planner_params
from mbot_slam_navigation.ros_msgs import pose_msg
from mbot_slam_navigation.transforms import check_planar_quaternion, compose2d, normalize_angle, quaternion_to_yaw

PLANNING, CONTROLLING, CLEARING = 'planning', 'controlling', 'clearing'
GLOBAL_PLANNERS = {'navfn/NavfnROS': 'NavfnROS', 'global_planner/GlobalPlanner': 'GlobalPlanner'}
LOCAL_PLANNERS = {'base_local_planner/TrajectoryPlannerROS': 'TrajectoryPlannerROS',
                  'dwa_local_planner/DWAPlannerROS': 'DWAPlannerROS'}
RECOVERY_TYPES = ('clear_costmap_recovery/ClearCostmapRecovery', 'rotate_recovery/RotateRecovery',
                  'mbot_slam_navigation/BackUpRecovery', 'moveback_recovery/MoveBackRecovery')


def pose_stamped(header, x: float, y: float, yaw: float) -> PoseStamped:
    """A planar pose as geometry_msgs/PoseStamped (``header`` is copied)."""
    return PoseStamped(header=header, pose=pose_msg(x, y, yaw))


class MoveBase:
    def __init__(self):
        self.tf = tf2_ros.Buffer(rospy.Duration(30.0))
        self.tf_listener = tf2_ros.TransformListener(self.tf)
        values = rospy.get_param('~', {})
        r = ParamReader(values, rospy.get_name(), rospy.logwarn)
        self.controller_frequency = r.number('controller_frequency', 20.0, positive=True)
        self.planner_frequency = r.number('planner_frequency', 0.0, minimum=0.0)
        self.controller_patience = r.number('controller_patience', 15.0, minimum=0.0)
        self.planner_patience = r.number('planner_patience', 5.0, minimum=0.0)
        self.max_planning_retries = r.integer('max_planning_retries', -1)
        # ROS's default is 0 (off); a robot rocking in place forever is what users meet instead.
        self.oscillation_timeout = r.number('oscillation_timeout', 20.0, minimum=0.0)
        self.oscillation_distance = r.number('oscillation_distance', 0.5, minimum=0.0)
        self.recovery_behavior_enabled = r.boolean('recovery_behavior_enabled', True)
        self.clearing_rotation_allowed = r.boolean('clearing_rotation_allowed', True)
        self.shutdown_costmaps = r.boolean('shutdown_costmaps', False)
        self.conservative_reset_dist = r.number('conservative_reset_dist', 3.0, minimum=0.0)
        self.make_plan_clear_costmap = r.boolean('make_plan_clear_costmap', True)
        self.make_plan_add_unreachable_goal = r.boolean('make_plan_add_unreachable_goal', True)
        global_type = r.string('base_global_planner', 'navfn/NavfnROS')
        local_type = r.string('base_local_planner', 'base_local_planner/TrajectoryPlannerROS')
        for key, value, known in (('base_global_planner', global_type, GLOBAL_PLANNERS),
                                  ('base_local_planner', local_type, LOCAL_PLANNERS)):
            if value not in known:
                guess = nearest_key(value, known)
                raise ParamError('parameter %s: unknown planner "%s"%s; this move_base provides %s' % (
                    r.where(key), value, ' (did you mean %s?)' % guess if guess else '', ', '.join(known)))
        self.global_ns = GLOBAL_PLANNERS[global_type]
        self.local_ns = LOCAL_PLANNERS[local_type]

        # Costmaps.
        self.global_costmap = CostmapROS('global_costmap', self.tf)
        self.local_costmap = CostmapROS('local_costmap', self.tf)

        # Global planner: navfn's keys (NavfnROS) or global_planner's (GlobalPlanner: use_dijkstra).
        g = ParamReader(values.get(self.global_ns, {}), r.where(self.global_ns), rospy.logwarn)
        if self.global_ns == 'GlobalPlanner':
            use_astar = not g.boolean('use_dijkstra', True)
        else:
            use_astar = g.boolean('use_astar', False)  # an addition of ours; navfn is Dijkstra only
        self.planner_args = dict(use_astar=use_astar, allow_unknown=g.boolean('allow_unknown', True),
                                 default_tolerance=g.number('default_tolerance', 0.0, minimum=0.0))
        for key in ('visualize_potential', 'planner_window_x', 'planner_window_y', 'planner_costmap_publish_frequency',
                    'use_quadratic', 'use_grid_path', 'old_navfn_behavior', 'lethal_cost', 'neutral_cost',
                    'cost_factor', 'publish_potential', 'orientation_mode', 'orientation_window_size', 'outline_map'):
            g.raw(key)
        g.report_unknown()
        self.planner = _core._GlobalPlanner(**self.planner_args)
        self.service_planner = _core._GlobalPlanner(**self.planner_args)  # ~make_plan, not racing the loop
        self.planner_lock = threading.Lock()

        # Local planner.
        if self.local_ns == 'DWAPlannerROS':
            rospy.logwarn('%s: DWAPlannerROS is served by TrajectoryPlannerROS with dwa: true, reading the '
                          'DWAPlannerROS namespace' % r.where('base_local_planner'))
        lvalues = dict(values.get(self.local_ns, {}))
        if self.local_ns == 'DWAPlannerROS':
            lvalues.setdefault('dwa', True)
        lp, self.local_ros = local_planner_params(lvalues, r.where(self.local_ns), rospy.logwarn,
                                                  self.controller_frequency)
        self.local_params = lp
        self.controller = TrajectoryController(lp, self.local_ros, self.local_costmap.config.footprint)

        self.recoveries = self._load_recoveries(r, values)
        skip = {'global_costmap', 'local_costmap', self.global_ns, self.local_ns} | {n for n, _, _ in self.recoveries}
        r.report_unknown(skip=skip)

        # ROS interfaces.
        self.cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self.plan_pub = rospy.Publisher('~%s/plan' % self.global_ns, Path, queue_size=1, latch=True)
        self.generic_plan_pub = rospy.Publisher('~plan', Path, queue_size=1, latch=True)
        self.local_plan_pub = rospy.Publisher('~%s/local_plan' % self.local_ns, Path, queue_size=1)
        self.local_global_plan_pub = rospy.Publisher('~%s/global_plan' % self.local_ns, Path, queue_size=1)
        self.goal_pub = rospy.Publisher('~current_goal', PoseStamped, queue_size=1, latch=True)
        self.action_goal_pub = rospy.Publisher('move_base/goal', MoveBaseActionGoal, queue_size=1)
        self.velocity = (0.0, 0.0, 0.0)
        rospy.Subscriber('odom', Odometry, self._on_odom, queue_size=1)
        rospy.Subscriber('move_base_simple/goal', PoseStamped, self._on_simple_goal, queue_size=1)
        rospy.Service('~make_plan', GetPlan, self._on_make_plan)
        rospy.Service('~clear_costmaps', Empty, self._on_clear_costmaps)
        self.server = actionlib.SimpleActionServer('move_base', MoveBaseAction, execute_cb=self._execute,
                                                   auto_start=False)
        if self.shutdown_costmaps:
            self.global_costmap.stop()
            self.local_costmap.stop()
        self.server.start()
        rospy.loginfo('move_base ready: global planner %s (%s), local planner %s%s, recoveries %s' % (
            global_type, 'A*' if use_astar else 'Dijkstra', local_type, ' (DWA)' if lp.dwa else '',
            ', '.join(n for n, _, _ in self.recoveries) if self.recovery_behavior_enabled else 'disabled'))

    # --- parameters ---------------------------------------------------------------------------------
    def _load_recoveries(self, r: ParamReader, values: Dict[str, Any]) -> List[Tuple[str, str, Dict[str, Any]]]:
        circumscribed = self.local_costmap.config.circumscribed_radius
        if r.has('recovery_behaviors'):
            spec = r.raw('recovery_behaviors')
            if not isinstance(spec, list) or not all(isinstance(b, dict) and 'name' in b and 'type' in b for b in spec):
                raise ParamError('parameter %s must be a list of {name: ..., type: ...}, got %r'
                                 % (r.where('recovery_behaviors'), spec))
            out = []
            for b in spec:
                if b['type'] not in RECOVERY_TYPES:
                    guess = nearest_key(b['type'], RECOVERY_TYPES)
                    raise ParamError('parameter %s: unknown recovery type "%s"%s; known: %s' % (
                        r.where('recovery_behaviors'), b['type'], ' (did you mean %s?)' % guess if guess else '',
                        ', '.join(RECOVERY_TYPES)))
                out.append((b['name'], b['type'], dict(values.get(b['name'], {}))))
        else:
            out = [('conservative_reset', RECOVERY_TYPES[0], {'reset_distance': self.conservative_reset_dist}),
                   ('rotate_recovery', RECOVERY_TYPES[1], {}),
                   ('back_up', RECOVERY_TYPES[2], {}),
                   ('aggressive_reset', RECOVERY_TYPES[0], {'reset_distance': 4.0 * circumscribed}),
                   ('rotate_recovery', RECOVERY_TYPES[1], {})]
            for name, _, params in out:
                params.update(values.get(name, {}) if isinstance(values.get(name), dict) else {})
        if not self.clearing_rotation_allowed:
            out = [b for b in out if b[1] != RECOVERY_TYPES[1]]
        checked = []
        for name, kind, params in out:
            pr = ParamReader(params, r.where(name), rospy.logwarn)
            if kind == RECOVERY_TYPES[0]:
                cfg = {'reset_distance': pr.number('reset_distance', 3.0, minimum=0.0),
                       'layer_names': pr.raw('layer_names', ['obstacle_layer']),
                       'affected_maps': pr.string('affected_maps', 'both'),
                       'force_updating': pr.boolean('force_updating', False),
                       'invert_area_to_clear': pr.boolean('invert_area_to_clear', False)}
                if cfg['affected_maps'] not in ('local', 'global', 'both'):
                    raise ParamError('parameter %s must be local, global or both' % pr.where('affected_maps'))
            elif kind == RECOVERY_TYPES[1]:
                cfg = {'sim_granularity': pr.number('sim_granularity', 0.017, positive=True),
                       'frequency': pr.number('frequency', 20.0, positive=True)}
            else:
                cfg = {'distance': pr.number('back_up_distance', 0.3, positive=True),
                       'speed': pr.number('back_up_speed', abs(self.local_params.escape_vel) or 0.1, positive=True),
                       'frequency': pr.number('frequency', 20.0, positive=True)}
            pr.report_unknown()
            checked.append((name, kind, cfg))
        return checked

    # --- inputs ---------------------------------------------------------------------------------------
    def _on_odom(self, msg: Odometry) -> None:
        t = msg.twist.twist
        self.velocity = (t.linear.x, t.linear.y, t.angular.z)

    def _on_simple_goal(self, msg: PoseStamped) -> None:
        rospy.loginfo('move_base: a goal from move_base_simple/goal (rviz 2D Nav Goal)')
        action_goal = MoveBaseActionGoal()
        action_goal.header.stamp = rospy.Time.now()
        action_goal.goal.target_pose = msg
        self.action_goal_pub.publish(action_goal)

    def _goal_in_frame(self, pose: PoseStamped, frame: str,
                       heading_required: bool = True) -> Tuple[Optional[Tuple[float, float, float]], str]:
        """The goal as (x, y, yaw) in ``frame`` (tf2 for another frame), or (None, why).

        ``heading_required`` False (make_plan requests, which often leave the orientation all zero)
        reads a zero quaternion as yaw 0 instead of refusing it."""
        o = pose.pose.orientation
        if not heading_required and (o.x, o.y, o.z, o.w) == (0.0, 0.0, 0.0, 0.0):
            yaw, note = 0.0, ''
        else:
            yaw, note = check_planar_quaternion((o.x, o.y, o.z, o.w), 'the goal orientation')
        if yaw is None:
            return None, note
        if note:
            rospy.logwarn('move_base: %s' % note)
        goal = (pose.pose.position.x, pose.pose.position.y, yaw)
        if not all(math.isfinite(v) for v in goal):
            return None, 'the goal position is not finite'
        source = pose.header.frame_id.lstrip('/')
        if not source:
            return None, 'the goal has an empty frame_id'
        if source != frame:
            try:
                t = self.tf.lookup_transform(frame, source, rospy.Time(0), rospy.Duration(0.5))
            except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
                return None, 'cannot transform the goal from frame "%s" to "%s": %s' % (source, frame, e)
            q = t.transform.rotation
            goal = compose2d((t.transform.translation.x, t.transform.translation.y, quaternion_to_yaw(q.x, q.y, q.z, q.w)),
                             goal)
        return goal, ''

    # --- planning --------------------------------------------------------------------------------------
    def _plan(self, planner, start, goal) -> Tuple[bool, np.ndarray, str]:
        """Plans on the global costmap; (ok, N x 2 path ending at the goal, why not)."""
        costmap, _ = self.global_costmap.snapshot()
        status, path, message, _, _ = planner.make_plan(costmap, np.array(start[:2], float), np.array(goal[:2], float))
        if status != 'ok':
            return False, path, '%s: %s' % (status, message)
        if len(path) and math.hypot(path[-1][0] - goal[0], path[-1][1] - goal[1]) <= costmap.resolution:
            path = np.vstack([path, [goal[0], goal[1]]])  # navfn ends its plan on the goal pose itself
        return True, path, ''

    def _publish_path(self, pubs, path: np.ndarray, frame: str, yaw: Optional[float] = None) -> None:
        msg = Path()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id = frame
        for i, (x, y) in enumerate(path):
            msg.poses.append(pose_stamped(msg.header, x, y, yaw if yaw is not None and i == len(path) - 1 else 0.0))
        for pub in pubs:
            pub.publish(msg)

    def _on_make_plan(self, req) -> GetPlanResponse:
        frame = self.global_costmap.config.global_frame
        resp = GetPlanResponse()
        resp.plan.header.frame_id = frame
        resp.plan.header.stamp = rospy.Time.now()
        if req.start.header.frame_id:
            start, why = self._goal_in_frame(req.start, frame, heading_required=False)
        else:
            start, why = self.global_costmap.lookup_robot_pose(), self.global_costmap.tf_problem
        goal, why_goal = self._goal_in_frame(req.goal, frame, heading_required=False)
        if start is None or goal is None:
            rospy.logerr('make_plan: %s' % (why or why_goal))
            return resp
        with self.planner_lock:
            tolerance = max(req.tolerance, self.planner_args['default_tolerance'])
            planner = self.service_planner
            if tolerance != self.planner_args['default_tolerance']:
                planner = _core._GlobalPlanner(self.planner_args['use_astar'], self.planner_args['allow_unknown'], tolerance)
            ok, path, why = self._plan(planner, start, goal)
        if not ok:
            rospy.logwarn('make_plan: no plan from (%.2f, %.2f) to (%.2f, %.2f): %s' % (start[0], start[1], goal[0],
                                                                                     goal[1], why))
            return resp
        for i, (x, y) in enumerate(path):
            resp.plan.poses.append(pose_stamped(resp.plan.header, x, y, goal[2] if i == len(path) - 1 else 0.0))
        return resp

    def _on_clear_costmaps(self, _req) -> EmptyResponse:
        self.global_costmap.reset_layers()
        self.local_costmap.reset_layers()
        rospy.loginfo('move_base: costmaps cleared')
        return EmptyResponse()

    # --- the action ----------------------------------------------------------------------------------
    def _stop(self) -> None:
        self.cmd_pub.publish(Twist())

    def _accept(self, target_pose: PoseStamped):
        goal, why = self._goal_in_frame(target_pose, self.global_costmap.config.global_frame)
        if goal is None:
            self.server.set_aborted(MoveBaseResult(), 'Aborting on goal because it was sent with an invalid '
                                    'quaternion or frame: %s' % why)
            rospy.logerr('move_base: goal rejected: %s' % why)
            return None
        header = Header(frame_id=self.global_costmap.config.global_frame, stamp=rospy.Time.now())
        ps = pose_stamped(header, *goal)
        self.goal_pub.publish(ps)
        rospy.loginfo('move_base: new goal (%.2f, %.2f, %.2f rad) in %s' % (goal[0], goal[1], goal[2], ps.header.frame_id))
        return goal

    def _execute(self, action_goal) -> None:
        if self.shutdown_costmaps:
            self.global_costmap.start()
            self.local_costmap.start()
        goal = self._accept(action_goal.target_pose)
        if goal is None:
            return
        self._reset(goal)
        rate = rospy.Rate(self.controller_frequency)
        try:
            while not rospy.is_shutdown():
                if self.server.is_preempt_requested():
                    if self.server.is_new_goal_available():
                        new = self.server.accept_new_goal()
                        goal = self._accept(new.target_pose)
                        if goal is None:
                            self._stop()
                            return
                        self._reset(goal)
                    else:
                        self._stop()
                        self.controller.reset()
                        self.server.set_preempted(MoveBaseResult(), 'Goal canceled')
                        rospy.loginfo('move_base: goal canceled; the robot is stopped')
                        return
                if self._cycle(goal):
                    return
                rate.sleep()
        finally:
            if self.shutdown_costmaps:
                self.global_costmap.stop()
                self.local_costmap.stop()
        self._stop()

    def _reset(self, goal) -> None:
        now = rospy.Time.now()
        self.goal = goal
        self.state = PLANNING
        self.plan = None
        self.new_plan = False
        self.last_plan_time = None
        self.last_valid_plan = now
        self.last_valid_control = now
        self.last_oscillation_reset = now
        self.oscillation_pose = None
        self.planning_retries = 0
        self.recovery_index = 0
        self.recovery_trigger = None
        self.why = ''
        self.controller.reset()

    def _abort(self, text: str) -> bool:
        self._stop()
        rospy.logerr('move_base: aborting the goal: %s' % text)
        self.server.set_aborted(MoveBaseResult(), text)
        return True

    def _cycle(self, goal) -> bool:
        """One control cycle; True when the goal is finished (succeeded or aborted)."""
        now = rospy.Time.now()
        pose = self.global_costmap.lookup_robot_pose()
        if pose is None:
            self._stop()
            why = 'tf: %s' % self.global_costmap.tf_problem
            rospy.logwarn_throttle(2, 'move_base: cannot get the robot pose: %s' % why)
            if (now - self.last_valid_control).to_sec() > self.controller_patience:
                return self._abort('Robot pose unavailable for more than controller_patience %.1f s (%s)'
                                   % (self.controller_patience, why))
            return False
        header = Header(frame_id=self.global_costmap.config.global_frame, stamp=now)
        self.server.publish_feedback(MoveBaseFeedback(base_position=pose_stamped(header, *pose)))

        if self.oscillation_pose is None or math.hypot(pose[0] - self.oscillation_pose[0],
                                                       pose[1] - self.oscillation_pose[1]) >= self.oscillation_distance:
            self.last_oscillation_reset = now
            self.oscillation_pose = pose
            if self.recovery_trigger == 'oscillation':
                self.recovery_index = 0

        current, why = self.local_costmap.is_current()
        if not current:
            self._stop()
            rospy.logwarn_throttle(2, "move_base: sensor data is out of date, not commanding the base for safety: %s" % why)
            if (now - self.last_valid_control).to_sec() > self.controller_patience:
                return self._abort('The local costmap was not current for controller_patience %.1f s: %s'
                                   % (self.controller_patience, why))
            return False

        replan_due = self.planner_frequency > 0 and self.last_plan_time is not None and \
            (now - self.last_plan_time).to_sec() >= 1.0 / self.planner_frequency
        if self.state == PLANNING or (self.state == CONTROLLING and replan_due):
            with self.planner_lock:
                ok, path, why = self._plan(self.planner, pose, goal)
            self.last_plan_time = now
            if ok:
                self.plan = path
                self.new_plan = True
                self.last_valid_plan = now
                self.planning_retries = 0
                self.state = CONTROLLING
                frame = self.global_costmap.config.global_frame
                self._publish_path((self.plan_pub, self.generic_plan_pub), path, frame, goal[2])
            else:
                self.why = why
                self.planning_retries += 1
                if self.state == CONTROLLING:
                    rospy.logwarn('move_base: replanning failed (%s); stopping instead of following the old plan' % why)
                    self.state = PLANNING
                self._stop()
                rospy.logwarn_throttle(2, 'move_base: no plan: %s' % why)
                if (now - self.last_valid_plan).to_sec() > self.planner_patience or \
                        (self.max_planning_retries >= 0 and self.planning_retries > self.max_planning_retries):
                    self.state = CLEARING
                    self.recovery_trigger = 'planning'
                else:
                    return False

        if self.state == CONTROLLING:
            if self.new_plan:
                self.controller.set_plan(self._to_local(self.plan), goal[2])
                self.new_plan = False
            local_pose = self.local_costmap.lookup_robot_pose() if self._frames_differ() else pose
            if local_pose is None:
                ok, cmd, why = False, (0.0, 0.0, 0.0), 'tf: %s' % self.local_costmap.tf_problem
            else:
                costmap, _ = self.local_costmap.snapshot()
                ok, cmd, why = self.controller.compute(costmap, local_pose, self.velocity)
            if self.controller.reached:
                self._stop()
                self.controller.reset()
                self.server.set_succeeded(MoveBaseResult(), 'Goal reached.')
                rospy.loginfo('move_base: goal reached')
                return True
            self._publish_local(local_pose)
            if self.oscillation_timeout > 0 and (now - self.last_oscillation_reset).to_sec() > self.oscillation_timeout:
                self._stop()
                self.why = 'moved less than oscillation_distance %.2f m in oscillation_timeout %.1f s' % (
                    self.oscillation_distance, self.oscillation_timeout)
                self.state = CLEARING
                self.recovery_trigger = 'oscillation'
            elif ok:
                t = Twist()
                t.linear.x, t.linear.y, t.angular.z = cmd
                self.cmd_pub.publish(t)
                self.last_valid_control = now
                if self.recovery_trigger == 'controlling':
                    self.recovery_index = 0
            else:
                self.why = why
                self._stop()
                if (now - self.last_valid_control).to_sec() > self.controller_patience:
                    self.state = CLEARING
                    self.recovery_trigger = 'controlling'
                else:
                    # No valid command: plan again from here (ROS does the same).
                    self.last_valid_plan = now
                    self.planning_retries = 0
                    self.state = PLANNING
                    return False

        if self.state == CLEARING:
            if self.recovery_trigger == 'planning' and self.why.startswith(('goal occupied', 'goal off the costmap')):
                # Turning or backing up cannot free a goal cell or bring it onto the map; only
                # clearing the costmaps might, so the motion recoveries are skipped.
                while self.recovery_index < len(self.recoveries) and \
                        self.recoveries[self.recovery_index][1] != RECOVERY_TYPES[0]:
                    self.recovery_index += 1
            if self.recovery_behavior_enabled and self.recovery_index < len(self.recoveries):
                name, kind, cfg = self.recoveries[self.recovery_index]
                rospy.logwarn('move_base: %s (%s); running recovery behaviour %s' % (
                    {'planning': 'no valid plan', 'controlling': 'no valid control',
                     'oscillation': 'oscillating'}[self.recovery_trigger], self.why, name))
                self._run_recovery(kind, cfg)
                self.recovery_index += 1
                self.last_oscillation_reset = rospy.Time.now()
                self.last_valid_plan = rospy.Time.now()
                self.last_valid_control = rospy.Time.now()
                self.planning_retries = 0
                self.state = PLANNING
                return False
            text = {'planning': 'Failed to find a valid plan. Even after executing recovery behaviors.',
                    'controlling': 'Failed to find a valid control. Even after executing recovery behaviors.',
                    'oscillation': 'Robot is oscillating. Even after executing recovery behaviors.'}[self.recovery_trigger]
            return self._abort('%s Last reason: %s' % (text, self.why))
        return False

    def _frames_differ(self) -> bool:
        return self.local_costmap.config.global_frame != self.global_costmap.config.global_frame

    def _to_local(self, plan: np.ndarray) -> np.ndarray:
        """The global plan in the local costmap's frame."""
        if not self._frames_differ():
            return plan
        src, dst = self.global_costmap.config.global_frame, self.local_costmap.config.global_frame
        try:
            t = self.tf.lookup_transform(dst, src, rospy.Time(0), rospy.Duration(0.2))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn('move_base: cannot transform the plan from %s to %s: %s' % (src, dst, e))
            return np.zeros((0, 2))
        q = t.transform.rotation
        base = (t.transform.translation.x, t.transform.translation.y, quaternion_to_yaw(q.x, q.y, q.z, q.w))
        return np.array([compose2d(base, (x, y, 0.0))[:2] for x, y in plan])

    def _publish_local(self, pose) -> None:
        frame = self.local_costmap.config.global_frame
        if self.local_plan_pub.get_num_connections() and len(self.controller.last_trajectory):
            self._publish_path((self.local_plan_pub,), np.array([p[:2] for p in self.controller.last_trajectory]), frame)
        if self.local_global_plan_pub.get_num_connections():
            self._publish_path((self.local_global_plan_pub,), self.controller.plan, frame)

    # --- recoveries ----------------------------------------------------------------------------------
    def _run_recovery(self, kind: str, cfg: Dict[str, Any]) -> None:
        if kind == RECOVERY_TYPES[0]:
            maps = {'local': [self.local_costmap], 'global': [self.global_costmap],
                    'both': [self.global_costmap, self.local_costmap]}[cfg['affected_maps']]
            for cm in maps:
                pose = cm.lookup_robot_pose()
                if pose is None:
                    continue
                if cfg['invert_area_to_clear']:
                    rospy.logwarn('clear_costmap_recovery: invert_area_to_clear clears everything here')
                    cm.reset_layers()
                else:
                    cm.reset_layers((pose[0], pose[1], cfg['reset_distance']))
                if cfg['force_updating']:
                    cm.update()
        elif kind == RECOVERY_TYPES[1]:
            self._rotate_recovery(cfg)
        else:
            self._back_up_recovery(cfg)

    def _footprint_free(self, pose) -> bool:
        costmap, _ = self.local_costmap.snapshot()
        fp = [np.array(p, float) for p in self.local_costmap.config.footprint]
        return costmap.footprint_cost(np.array(pose, float), fp, True) >= 0

    def _rotate_recovery(self, cfg: Dict[str, Any]) -> None:
        """rotate_recovery: one full turn in place, stopping before a collision."""
        p = self.local_params
        max_vel = self.local_ros['max_rotational_vel']
        min_vel = p.min_in_place_vel_theta
        rate = rospy.Rate(cfg['frequency'])
        start = self.local_costmap.lookup_robot_pose()
        if start is None:
            return
        turned, last_yaw, tolerance = 0.0, start[2], 0.1
        while not rospy.is_shutdown() and not self.server.is_preempt_requested():
            pose = self.local_costmap.lookup_robot_pose()
            if pose is None:
                break
            turned += abs(normalize_angle(pose[2] - last_yaw))
            last_yaw = pose[2]
            left = 2 * math.pi - turned
            if left <= tolerance:
                break
            sim = 0.0
            while sim < left:  # the footprint along the rest of the turn
                if not self._footprint_free((pose[0], pose[1], pose[2] + sim)):
                    rospy.logwarn('rotate_recovery: cannot rotate in place, a collision is %.2f rad ahead' % sim)
                    self._stop()
                    return
                sim += cfg['sim_granularity']
            vel = min(max(math.sqrt(2 * p.acc_lim_theta * left), min_vel), max_vel)
            t = Twist()
            t.angular.z = vel
            self.cmd_pub.publish(t)
            rate.sleep()
        self._stop()

    def _back_up_recovery(self, cfg: Dict[str, Any]) -> None:
        """Backs straight up by ``back_up_distance`` at ``back_up_speed`` while the footprint stays clear."""
        rate = rospy.Rate(cfg['frequency'])
        start = self.local_costmap.lookup_robot_pose()
        if start is None:
            return
        while not rospy.is_shutdown() and not self.server.is_preempt_requested():
            pose = self.local_costmap.lookup_robot_pose()
            if pose is None or math.hypot(pose[0] - start[0], pose[1] - start[1]) >= cfg['distance']:
                break
            step = 0.05
            behind = (pose[0] - step * math.cos(pose[2]), pose[1] - step * math.sin(pose[2]), pose[2])
            if not self._footprint_free(behind):
                rospy.logwarn('back_up recovery: an obstacle behind the robot; stopped after %.2f m'
                              % math.hypot(pose[0] - start[0], pose[1] - start[1]))
                break
            t = Twist()
            t.linear.x = -cfg['speed']
            self.cmd_pub.publish(t)
            rate.sleep()
        self._stop()


def main() -> None:
    rospy.init_node('move_base')
    try:
        MoveBase()
    except ParamError as e:
        rospy.logfatal('move_base: %s' % e)
        raise SystemExit(1)
    rospy.spin()
