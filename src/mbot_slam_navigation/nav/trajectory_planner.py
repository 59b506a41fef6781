"""TrajectoryPlannerROS's behaviour around the C++ trajectory planner, ROS-free.

``local_planner_params`` reads the ``TrajectoryPlannerROS`` namespace with ROS's names, deprecated
names and effective defaults; ``TrajectoryController`` is the per-cycle logic of
computeVelocityCommands: prune the plan, goal tolerances (with latch_xy_goal_tolerance), stop with
the acceleration limits, then rotate to the goal yaw, else the best rollout trajectory. Poses are
(x [m], y [m], yaw [rad]) in the local costmap's frame, velocities (vx, vy, vtheta) in the robot's.
"""
import math
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.params import ParamError, ParamReader, Warn
from mbot_slam_navigation.transforms import normalize_angle

STOPPED_TRANS = 1e-2  # [m/s] ROS's trans_stopped_velocity
STOPPED_ROT = 1e-2    # [rad/s] rot_stopped_velocity


def local_planner_params(values: Optional[Dict[str, Any]], ns: str, warn: Warn,
                         controller_frequency: float) -> Tuple[Any, Dict[str, Any]]:
    """(_core._LocalPlannerParams, the ROS-side settings) from a TrajectoryPlannerROS namespace.

    ``controller_frequency`` is move_base's; a ``controller_frequency`` inside the namespace wins for
    the planner's sim_period, as ROS's searchParam finds the nearer one.
    """
    r = ParamReader(values, ns, warn)
    p = _core._LocalPlannerParams()
    p.acc_lim_x = r.number('acc_lim_x', 2.5, minimum=0.0)
    p.acc_lim_y = r.number('acc_lim_y', 2.5, minimum=0.0)
    p.acc_lim_theta = r.deprecated('acc_lim_theta', 'acc_lim_th', 3.2)
    for wrong in ('acc_limit_x', 'acc_limit_y', 'acc_limit_th'):
        if r.has(wrong):
            r.read_keys.add(wrong)
            warn('parameter %s is not read; the name is %s (the old documentation was wrong)'
                 % (r.where(wrong), wrong.replace('acc_limit', 'acc_lim')))
    p.max_vel_x = r.number('max_vel_x', 0.55, minimum=0.0)
    p.min_vel_x = r.number('min_vel_x', 0.0, minimum=0.0)
    if r.has('max_rotational_vel'):
        # ROS reads it at start-up, then dynamic_reconfigure overwrites it with max/min_vel_theta.
        r.read_keys.add('max_rotational_vel')
        warn('parameter %s has no effect in TrajectoryPlannerROS (dynamic_reconfigure replaces it with '
             'max_vel_theta / min_vel_theta); rotate_recovery still reads it' % r.where('max_rotational_vel'))
    p.max_vel_theta = r.number('max_vel_theta', 1.0, minimum=0.0)
    p.min_vel_theta = r.number('min_vel_theta', -1.0)
    if p.min_vel_theta > 0:
        raise ParamError('parameter %s must be <= 0 (it is the fastest clockwise turn), got %g'
                         % (r.where('min_vel_theta'), p.min_vel_theta))
    p.min_in_place_vel_theta = r.deprecated('min_in_place_vel_theta', 'min_in_place_rotational_vel', 0.4)
    backup = -0.1
    if r.has('backup_vel'):
        warn('parameter %s is deprecated; use escape_vel' % r.where('backup_vel'))
        backup = r.number('backup_vel', -0.1)
    p.escape_vel = r.number('escape_vel', backup)
    if p.escape_vel >= 0:
        warn('parameter %s is %g: a non-negative escape velocity moves the robot forward when it should back up'
             % (r.where('escape_vel'), p.escape_vel))
    p.sim_time = r.number('sim_time', 1.7, positive=True)
    p.sim_granularity = r.number('sim_granularity', 0.025, positive=True)
    p.angular_sim_granularity = r.number('angular_sim_granularity', 0.025, positive=True)
    p.vx_samples = r.integer('vx_samples', 20)
    p.vtheta_samples = r.integer('vtheta_samples', 20)
    for key in ('vx_samples', 'vtheta_samples'):
        if getattr(p, key) < 1:
            warn('parameter %s is %d; at least one sample is taken' % (r.where(key), getattr(p, key)))
            setattr(p, key, 1)
    p.path_distance_bias = r.deprecated('path_distance_bias', 'pdist_scale', 0.6)
    p.goal_distance_bias = r.deprecated('goal_distance_bias', 'gdist_scale', 0.8)
    p.occdist_scale = r.number('occdist_scale', 0.01, minimum=0.0)
    if not r.has('meter_scoring'):
        warn('parameter %s is not set: the distance biases count cells, so the behaviour changes with the costmap '
             'resolution; set it to true' % r.where('meter_scoring'))
    p.meter_scoring = r.boolean('meter_scoring', False)
    p.heading_lookahead = r.number('heading_lookahead', 0.325, minimum=0.0)
    p.heading_scoring = r.boolean('heading_scoring', False)
    p.heading_scoring_timestep = r.number('heading_scoring_timestep', 0.1, minimum=0.0)
    p.oscillation_reset_dist = r.number('oscillation_reset_dist', 0.05, minimum=0.0)
    p.escape_reset_dist = r.number('escape_reset_dist', 0.10, minimum=0.0)
    p.escape_reset_theta = r.number('escape_reset_theta', math.pi / 2, minimum=0.0)
    p.holonomic_robot = r.boolean('holonomic_robot', True)
    p.dwa = r.boolean('dwa', False)
    p.simple_attractor = r.boolean('simple_attractor', False)
    y_vels = r.raw('y_vels', '-0.3,-0.1,0.1,-0.3')
    try:
        p.y_vels = [float(v) for v in (y_vels.replace(',', ' ').split() if isinstance(y_vels, str) else y_vels)]
    except (TypeError, ValueError):
        raise ParamError('parameter %s must be a list of speeds, got %r' % (r.where('y_vels'), y_vels))
    frequency = r.number('controller_frequency', controller_frequency) if r.has('controller_frequency') else controller_frequency
    if frequency <= 0:
        warn('controller_frequency %g is not positive; the planner assumes 20 Hz' % frequency)
        frequency = 20.0
    p.sim_period = 1.0 / frequency
    ros = {
        'xy_goal_tolerance': r.number('xy_goal_tolerance', 0.10, minimum=0.0),
        'yaw_goal_tolerance': r.number('yaw_goal_tolerance', 0.05, minimum=0.0),
        'latch_xy_goal_tolerance': r.boolean('latch_xy_goal_tolerance', False),
        'prune_plan': r.boolean('prune_plan', True),
        'stop_time_buffer': r.number('stop_time_buffer', 0.2, minimum=0.0),
        'max_rotational_vel': float(r.values.get('max_rotational_vel', 1.0)),
    }
    for key in ('world_model', 'restore_defaults', 'point_grid', 'x_goal_tolerance', 'y_goal_tolerance'):
        r.read_keys.add(key)
    r.report_unknown()
    return p, ros


def prune_plan(plan: np.ndarray, pose: Sequence[float]) -> np.ndarray:
    """ROS's prunePlan: drops the plan points the robot has passed (up to the first within 1 m)."""
    if len(plan) == 0:
        return plan
    d2 = (plan[:, 0] - pose[0]) ** 2 + (plan[:, 1] - pose[1]) ** 2
    near = np.nonzero(d2 < 1.0)[0]
    return plan[near[0]:] if len(near) else plan


def _sign(v: float) -> float:
    return 1.0 if v >= 0 else -1.0


class TrajectoryController:
    """One TrajectoryPlannerROS instance: ``set_plan`` then ``compute`` each control cycle."""

    def __init__(self, params, ros: Dict[str, Any], footprint: List[Tuple[float, float]]):
        self.params = params
        self.ros = ros
        self.footprint = [np.array(p, float) for p in footprint]
        self.core = _core._LocalPlanner(params, self.footprint)
        self.plan = np.zeros((0, 2))
        self.goal_yaw = 0.0
        self.reached = False
        self.latched = False
        self.rotating_to_goal = False
        self.last_trajectory = []
        self.last_cost = 0.0

    def set_plan(self, plan: np.ndarray, goal_yaw: float) -> None:
        self.plan = np.asarray(plan, float).reshape(-1, 2)
        self.goal_yaw = goal_yaw
        self.reached = False
        self.latched = False

    def reset(self) -> None:
        self.core.reset_oscillation()
        self.rotating_to_goal = False
        self.reached = False
        self.latched = False

    def _check(self, costmap, pose, vel, cmd) -> bool:
        return self.core.score_trajectory(costmap, np.array(pose, float), np.array(vel, float), np.array(cmd, float)) >= 0

    def compute(self, costmap, pose: Sequence[float], vel: Sequence[float]) -> Tuple[bool, Tuple[float, float, float], str]:
        """(valid, (vx, vy, vtheta), why not). ``reached`` turns true once within both tolerances."""
        p, ros = self.params, self.ros
        if len(self.plan) == 0:
            return False, (0.0, 0.0, 0.0), 'no global plan'
        if ros['prune_plan']:
            self.plan = prune_plan(self.plan, pose)
        self.core.set_plan([np.array(q) for q in self.plan])
        goal = self.plan[-1]
        self.last_trajectory = []
        if self.latched or math.hypot(goal[0] - pose[0], goal[1] - pose[1]) <= ros['xy_goal_tolerance']:
            if ros['latch_xy_goal_tolerance']:
                self.latched = True
            diff = normalize_angle(self.goal_yaw - pose[2])
            if abs(diff) <= ros['yaw_goal_tolerance']:
                self.rotating_to_goal = False
                self.latched = False
                self.reached = True
                return True, (0.0, 0.0, 0.0), ''
            self.core.update_grids(costmap, np.array(pose, float))
            moving = abs(vel[0]) > STOPPED_TRANS or abs(vel[1]) > STOPPED_TRANS or abs(vel[2]) > STOPPED_ROT
            if moving and not self.rotating_to_goal:
                # Slow down with the acceleration limits over one control period.
                cmd = (_sign(vel[0]) * max(0.0, abs(vel[0]) - p.acc_lim_x * p.sim_period),
                       _sign(vel[1]) * max(0.0, abs(vel[1]) - p.acc_lim_y * p.sim_period),
                       _sign(vel[2]) * max(0.0, abs(vel[2]) - p.acc_lim_theta * p.sim_period))
                if self._check(costmap, pose, vel, cmd):
                    return True, cmd, ''
                return False, (0.0, 0.0, 0.0), 'cannot slow down safely at the goal'
            self.rotating_to_goal = True
            vth = min(p.max_vel_theta, max(p.min_in_place_vel_theta, diff)) if diff > 0 else \
                max(p.min_vel_theta, min(-p.min_in_place_vel_theta, diff))
            fastest = abs(vel[2]) + p.acc_lim_theta * p.sim_period
            slowest = abs(vel[2]) - p.acc_lim_theta * p.sim_period
            vth = _sign(vth) * min(max(abs(vth), slowest), fastest)
            vth = _sign(vth) * min(math.sqrt(2 * p.acc_lim_theta * abs(diff)), abs(vth))  # stop on the yaw
            vth = min(p.max_vel_theta, max(p.min_in_place_vel_theta, vth)) if vth > 0 else \
                max(p.min_vel_theta, min(-p.min_in_place_vel_theta, vth))
            if self._check(costmap, pose, vel, (0.0, 0.0, vth)):
                return True, (0.0, 0.0, vth), ''
            return False, (0.0, 0.0, 0.0), 'cannot turn to the goal orientation without a collision'
        self.rotating_to_goal = False
        cmd, cost, points = self.core.find_best_path(costmap, np.array(pose, float), np.array(vel, float))
        self.last_trajectory = points
        self.last_cost = cost
        if cost < 0:
            return False, (0.0, 0.0, 0.0), 'no valid trajectory (every sampled command collides or leaves the plan)'
        return True, (float(cmd[0]), float(cmd[1]), float(cmd[2])), ''
