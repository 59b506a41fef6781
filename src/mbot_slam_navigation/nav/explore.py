"""explore: autonomous frontier exploration over move_base (stands in for explore_lite, and finishes).

Every 1/planner_frequency seconds: frontiers of the SLAM map, each one's goal = its cell nearest to
the robot by path on move_base's global costmap (so never inside an obstacle, never unreachable),
cost = potential_scale * path length - gain_scale * frontier size (counted up to gain_size_max); the
current goal is kept unless another beats it by `hysteresis`, and a goal left for a better one does
not take the robot back from the current one for `switch_back_after` (60 s; as the map grows two
frontiers' costs can take turns, and the robot would reach neither); a goal move_base aborts, or one
the robot makes no progress towards within progress_timeout, is blacklisted for blacklist_timeout
with its frontier (after max_tries failures that frontier is given up, whatever goal it yields
next); a goal reached is not sent again, and frontier cells near it count only when nothing else
is left and their frontier is at least twice min_frontier_size (a room seen only from its door).
Every run ends, with an outcome:
- `complete`: no reachable frontier left (frontiers given up or unreachable are listed in the report);
- `timeout`: max_duration [simulated s] passed (0: no limit);
- `stuck`: goals fail, the robot has not moved for progress_timeout and move_base cannot move it;
  the explorer then backs it out along its own recent path by cmd_vel, checking the laser (a
  warning says so); if that fails twice, or the robot is boxed in with no path of its own, the
  robot is stopped and the exploration ends;
- `error`: an exception inside the explorer (a bug): logged with its traceback, the robot stopped,
  the report written with the error, rather than a node that dies and leaves the launch running.
Then the robot returns to its start pose (not when stuck or on error; within return_timeout), the report is
written to ~report_dir if set (mbot_slam_navigation.explore_report), and `explore/complete`
(std_msgs/Bool, latched) turns true.

Parameters: read_parameters() (the reference page: docs/nodes/explore.md): explore_lite's names and
defaults, then ours.

A team (launch/multi_explore.launch): with team_topic set (e.g. /explore/team), each explorer says
where its robot is and where it goes (mbot_slam_navigation/ExplorerState, under robot_name, default
its namespace; every cycle and every second) and hears the others: a frontier whose goal lies
within claim_radius (2.0 m) of a teammate's goal is left to it, and one nearer to a teammate than
to this robot costs more (team.share_out); of two robots heading for one place the one whose name
sorts first keeps it. A robot whose frontiers are all claimed waits; the team's exploration is complete
for a robot when no frontier is left to anyone.
"""
import math
import os
import threading
import time
import traceback
from types import SimpleNamespace
from typing import List, Optional, Sequence, Tuple

import numpy as np
import rosgraph
import rospy
from rospy.numpy_msg import numpy_msg
from actionlib import SimpleGoalState
import tf2_ros
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import Point, PolygonStamped, Twist, Vector3
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from map_msgs.msg import OccupancyGridUpdate
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan
from std_msgs.msg import Bool, ColorRGBA
from std_srvs.srv import Empty, Trigger, TriggerResponse
from visualization_msgs.msg import Marker, MarkerArray

from mbot_slam_navigation import _core, explore_report
from mbot_slam_navigation.batched_reads import clock_at_most_every
from mbot_slam_navigation.home_rooms import load_rooms, rooms_file_of
from mbot_slam_navigation.host_check import address_problem
from mbot_slam_navigation.lazy_tf import LazyTransformBuffer
from mbot_slam_navigation.maps.updates import FollowedMap, grid_of
from mbot_slam_navigation.msg import Contact, ExplorerState
from mbot_slam_navigation.nav.action_client import SimpleActionClient
from mbot_slam_navigation.nav.escape import backtrack_target, escape_command
from mbot_slam_navigation.nav.explore_state import ELIGIBLE, ExploreState, MotionWatch, Plateau
from mbot_slam_navigation.nav.frontiers import (GAIN_SCALE, MIN_FRONTIER_SIZE, POTENTIAL_SCALE, Frontier, GivenUp,
                                                Grid, passable, rank_frontiers)
from mbot_slam_navigation.nav.team import Teammate, share_out, yields_goal
from mbot_slam_navigation.nav.tour import tour_order
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.ros_msgs import pose_msg
from mbot_slam_navigation.sim.ground_truth import load_truth
from mbot_slam_navigation.topic_watch import WatchedSubscriber
from mbot_slam_navigation.transforms import compose2d, inverse2d, quaternion_to_yaw


# [s per m of path] the way back to the start may take: 0.1 m/s, turns and replanning included
RETURN_S_PER_M = 10.0
BOXED_IN_M2 = 2.0  # [m^2] reachable on the global costmap below which the robot is stuck, not done
# A frontier near a place visited before is gone back to (when nothing else is left) only if it is
# this many times min_frontier_size: in the apartment the ones of 0.8-0.9 m were nooks that no
# trip showed; the home's kitchen, seen only from its door, left one of 2.25 m.
REVISIT_SIZE_FACTOR = 2.0
MAX_TOUR_FRONTIERS = 40  # ~tour_frontiers above this is capped, with a warning (see Explore.__init__)


def sim_sleep(seconds: float, poll: float = 0.02) -> None:
    """Sleeps `seconds` of ROS time (simulated under /use_sim_time) by polling the wall clock every
    `poll` s. rospy.sleep wakes its thread at every /clock message (100 Hz simulated, so 800 times a
    wall second at 8x real time) only to sleep again. Returns early on shutdown or when time jumps
    back (a simulation reset)."""
    start = rospy.Time.now()
    end = start + rospy.Duration(seconds)
    while not rospy.is_shutdown():
        now = rospy.Time.now()
        if now >= end or now < start:
            return
        time.sleep(poll)


def read_parameters(r: ParamReader, default_robot_name: str = 'robot') -> SimpleNamespace:
    """explore's parameters: explore_lite's names and defaults, then ours; checked (ParamError)."""
    c = SimpleNamespace()
    c.robot_base_frame = r.frame('robot_base_frame', 'base_footprint', "the robot's base frame")
    c.global_frame = r.frame('global_frame', 'map', 'the map frame')
    c.costmap_topic = r.string('costmap_topic', 'move_base/global_costmap/costmap',
                               "move_base's global costmap: goals are placed and paths measured on it")
    r.string('costmap_updates_topic', '', "explore_lite's; not used (the full costmap topic is enough here)")
    c.map_topic = r.string('map_topic', 'map', "ours: the SLAM map, whose frontiers are explored")
    c.subscribe_to_updates = r.boolean('subscribe_to_updates', False,
                                       "ours: also read <map_topic>_updates (map_msgs/OccupancyGridUpdate), as "
                                       "costmap_2d's static layer does: a map sent whole only when it grows "
                                       "(map_merge's publish_updates)")
    c.planner_frequency = r.number('planner_frequency', 0.33, '[Hz] how often frontiers are found and a goal chosen',
                                   positive=True)
    c.potential_scale = r.number('potential_scale', POTENTIAL_SCALE, "weight of a frontier's path length in its cost", minimum=0.0)
    c.gain_scale = r.number('gain_scale', GAIN_SCALE, "weight of a frontier's size in its cost", minimum=0.0)
    c.gain_size_max = r.number('gain_size_max', 5.0,
                               '[m] ours: a frontier counts in its gain up to this size (0: no cap)', minimum=0.0)
    if r.number('orientation_scale', 0.0, "explore_lite's; not used (goals face the way the robot goes)") != 0.0:
        r.warn('explore: orientation_scale is not used (goals face the way the robot goes)')
    c.min_frontier_size = r.number('min_frontier_size', MIN_FRONTIER_SIZE, '[m] smallest frontier explored',
                                   minimum=0.0)
    c.min_unknown_area = r.number('min_unknown_area', 3.0,
                                  '[m^2] ours: enclosed unknown space smaller than this (the inside of furniture) makes '
                                  'no frontier unless free floor bounds most of it', minimum=0.0)
    c.min_unknown_beside = r.number('min_unknown_beside', 0.25,
                                    '[m^2] ours: a frontier with less unknown space within 1 m is given up (a sliver '
                                    'the laser grazed)', minimum=0.0)
    c.tour_frontiers = r.integer('tour_frontiers', 20,
                                 'ours: the best this many frontiers are re-ranked by the shortest tour through their '
                                 'goals (at most %d; 0 or 1: greedy as explore_lite)' % MAX_TOUR_FRONTIERS, minimum=0)
    if c.tour_frontiers > MAX_TOUR_FRONTIERS:
        # a tour beyond 12 goals costs about n^4 steps and a path-length field per goal: 5 ms at
        # 40, 24 ms at 60, seconds at a few hundred, every cycle
        r.warn('explore: ~tour_frontiers %d: more than %d makes every cycle slow; using %d'
               % (c.tour_frontiers, MAX_TOUR_FRONTIERS, MAX_TOUR_FRONTIERS))
        c.tour_frontiers = MAX_TOUR_FRONTIERS
    c.visualize = r.boolean('visualize', True, 'publish the frontiers on explore/frontiers')
    c.transform_tolerance = r.number('transform_tolerance', 0.3, "[s] how old the robot's pose may be", positive=True)
    c.progress_timeout = r.number('progress_timeout', 30.0,
                                  '[s] a goal the robot makes no progress towards for this long is blacklisted',
                                  positive=True)
    c.blacklist_timeout = r.number('blacklist_timeout', 60.0, '[s] ours: how long a failed goal stays blacklisted',
                                   minimum=0.0)
    c.max_tries = r.integer('max_tries', 2, 'ours: failures after which a frontier is given up', minimum=1)
    c.hysteresis = r.number('hysteresis', 1.0, 'ours: another goal must beat the current one by this cost', minimum=0.0)
    c.switch_back_after = r.number('switch_back_after', 60.0,
                                   '[s] ours: a goal left for a better one is not taken again for this long',
                                   minimum=0.0)
    c.max_goals_per_place = r.integer('max_goals_per_place', 5,
                                      'ours: goals sent within 0.6 m of one place before its frontier is given up',
                                      minimum=1)
    c.return_to_start = r.boolean('return_to_start', True, 'ours: drive back to the start pose when done')
    c.report_dir = r.string('report_dir', '', "ours: where the report is written ('': none)")
    c.world_name = r.string('world_name', '',
                            "ours: the world file, for ground-truth figures ('': the simulator's /gazebo/world_name)")
    c.robot_radius = r.number('robot_radius', 0.2, "[m] ours: the robot's radius (reachability, backing out)",
                              positive=True)
    c.progress_period = r.number('progress_period', 10.0, '[s] ours: between progress lines', positive=True)
    c.shutdown_when_done = r.boolean('shutdown_when_done', False, 'ours: end the launch when the exploration ends')
    c.max_duration = r.number('max_duration', 0.0, '[s] ours: simulated time before the outcome is timeout (0: none)',
                              minimum=0.0)
    c.startup_timeout = r.number('startup_timeout', 300.0,
                                 '[s] ours: wall time to wait for move_base, the map, the costmap and the pose',
                                 positive=True)
    c.read_period = r.number('read_period', 0.02,
                             '[s] ours: /clock and /tf are read at most this often, in batches (0: every message)',
                             minimum=0.0)
    c.return_timeout = r.number('return_timeout', 120.0, '[s] ours: time allowed to return to the start (at least; '
                                '10 s per metre of the way back when that is more)',
                                positive=True)
    c.escape_distance = r.number('escape_distance', 0.6, '[m] ours: how far to back out along the path when stuck',
                                 positive=True)
    c.escape_speed = r.number('escape_speed', 0.1, '[m/s] ours: backing-out speed', positive=True)
    c.escape_timeout = r.number('escape_timeout', 30.0, '[s] ours: time allowed to back out', positive=True)
    c.scan_topic = r.string('scan_topic', 'scan', 'ours: the laser, checked while backing out')
    c.cmd_vel_topic = r.string('cmd_vel_topic', 'cmd_vel', 'ours: velocity commands while backing out')
    c.model_name = r.string('model_name', '',
                            "ours: the simulator's model whose contacts count as collisions ('': every robot's)")
    c.team_topic = r.string('team_topic', '', "ours: the team's topic (e.g. /explore/team; '': alone)")
    c.robot_name = r.string('robot_name', default_robot_name, "ours: this robot's name in the team (default: namespace)")
    c.claim_radius = r.number('claim_radius', 2.0, "[m] ours: a frontier whose goal is this near a teammate's goal "
                              "is left to it", minimum=0.0)
    boundary = r.raw('boundary', [], "[m] ours: [[x, y], ...] in global_frame: explore only inside this polygon "
                     "(frontier_exploration's; also the explore/boundary topic); []: everywhere", 'list')
    c.boundary = polygon_of(boundary, r.where('boundary'))
    c.keepout_mask_topic = r.string('keepout_mask_topic', 'keepout_filter_mask',
                                    "ours: a keep-out filter's mask (nav_msgs/OccupancyGrid, map frame; 100: forbidden), "
                                    "as move_base's KeepoutFilter reads it: its zones make no frontiers and the report "
                                    "leaves them out of the reachable space; '': none")
    return c


def polygon_of(points, where: str) -> Optional[np.ndarray]:
    """(N, 2) [m] from [[x, y], ...], None for []; ParamError naming `where` for anything else."""
    if isinstance(points, (list, tuple)) and not points:
        return None
    if not isinstance(points, (list, tuple)):
        raise ParamError('%s must be a list of at least 3 [x, y] points, got %r' % (where, points))
    try:
        polygon = np.array([[float(p[0]), float(p[1])] for p in points if len(p) == 2], float)
    except (TypeError, ValueError, IndexError):
        polygon = np.zeros((0, 2))
    if len(polygon) != len(points) or len(polygon) < 3 or not np.all(np.isfinite(polygon)):
        raise ParamError('%s must be a list of at least 3 [x, y] points, got %r' % (where, points))
    return polygon


class Explore:
    def __init__(self):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        c = read_parameters(r, rospy.get_namespace().strip('/') or 'robot')
        r.report_unknown()
        problem = address_problem(rosgraph.get_master_uri(), rospy.get_node_uri() or '')
        if problem:
            rospy.logerr('explore: %s', problem)
        self.base_frame = c.robot_base_frame
        self.global_frame = c.global_frame
        self.costmap_topic = costmap_topic = c.costmap_topic
        self.map_topic = map_topic = c.map_topic
        self.period = 1.0 / c.planner_frequency
        self.potential_scale, self.gain_scale, self.gain_size_max = c.potential_scale, c.gain_scale, c.gain_size_max
        self.min_frontier_size = c.min_frontier_size
        self.min_unknown_area, self.min_unknown_beside = c.min_unknown_area, c.min_unknown_beside
        self.tour_frontiers = c.tour_frontiers
        self.visualize = c.visualize
        self.transform_tolerance = c.transform_tolerance
        self.state = ExploreState(progress_timeout=c.progress_timeout, blacklist_timeout=c.blacklist_timeout,
                                  max_tries=c.max_tries, hysteresis=c.hysteresis,
                                  switch_back_after=c.switch_back_after, max_goals_per_place=c.max_goals_per_place)
        self.return_to_start = c.return_to_start
        self.report_dir = c.report_dir
        self.world_name = c.world_name or rospy.get_param('/gazebo/world_name', '')
        self.world_from_map = (0.0, 0.0, 0.0)  # the map frame in the world (map_in_world), for the report
        self.robot_radius = c.robot_radius
        self.progress_period = c.progress_period
        self.shutdown_when_done = c.shutdown_when_done
        self.max_duration = c.max_duration
        self.startup_timeout = c.startup_timeout
        read_period = c.read_period
        self.return_timeout = c.return_timeout
        self.escape_distance, self.escape_speed, self.escape_timeout = c.escape_distance, c.escape_speed, c.escape_timeout
        scan_topic, cmd_vel_topic = c.scan_topic, c.cmd_vel_topic
        self.model_name = c.model_name
        team_topic = c.team_topic
        self.robot_name = c.robot_name
        self.claim_radius = c.claim_radius

        self.map: Optional[Grid] = None
        self.map_with_stamp: Tuple[Optional[Grid], rospy.Time] = (None, rospy.Time(0))
        self.costmap: Optional[Grid] = None
        self.error = ''  # an internal error that ended the exploration (outcome 'error')
        self.collisions = 0
        self.start_time: Optional[rospy.Time] = None  # set when exploring starts
        self.path: List[Tuple[float, float]] = []
        self.path_time = -math.inf                     # [s] ROS time of the path's last point
        self.goals: List[Tuple[float, float, bool]] = []  # (x, y, reached)
        self.curve: List[Tuple[float, float]] = []         # (simulated s since start, known m^2)
        self.given_up: List[GivenUp] = []
        self.motion = MotionWatch(self.state.progress_distance)
        self.plateau = Plateau()
        self.scan: Optional[LaserScan] = None
        # /tf read lazily: only the pose lookups (a few a second) deserialize it; a
        # TransformListener would deserialize all 87 messages a simulated second. /clock and /tf
        # read in batches (batched_reads): each message woke a thread, at 6x real time 1,100 a
        # wall second for a pose and a time wanted a few times a second.
        self.tf = LazyTransformBuffer(read_period=read_period)
        if read_period > 0.0:
            clock_at_most_every(read_period)
        # numpy_msg: the grids arrive as numpy arrays, not as tuples of Python ints (a 53k-cell
        # grid: 0.01 ms instead of 2.4 ms here)
        # Started by the same roslaunch as SLAM and move_base: a connection rospy lost while both
        # registered is made again during the start-up wait (topic_watch).
        self.map_lock = threading.Lock()  # the whole map's and the updates' callbacks run in two threads
        self.followed = FollowedMap()
        if c.subscribe_to_updates:
            rospy.Subscriber(map_topic + '_updates', numpy_msg(OccupancyGridUpdate), self.on_map_update, queue_size=100)
        self.inputs = [WatchedSubscriber(map_topic, numpy_msg(OccupancyGrid), self.on_map, queue_size=1,
                                         buff_size=2 ** 24),
                       WatchedSubscriber(costmap_topic, numpy_msg(OccupancyGrid), self.on_costmap, queue_size=1,
                                         buff_size=2 ** 24)]
        rospy.Subscriber('/gazebo/contacts', Contact, self.on_contact)
        self.scan_topic = scan_topic  # subscribed only while backing out
        self.cmd_pub = rospy.Publisher(cmd_vel_topic, Twist, queue_size=1)  # only while backing out
        self.marker_pub = rospy.Publisher('explore/frontiers', MarkerArray, queue_size=1, latch=True)
        self.done_pub = rospy.Publisher('explore/complete', Bool, queue_size=1, latch=True)
        self.done_pub.publish(Bool(False))
        self.move_base = SimpleActionClient('move_base', MoveBaseAction, feedback=False)  # never read here
        # Pause (m-explore's explore/resume topic, and explore/pause, explore/resume services):
        # while paused no goal is sent, the current one is cancelled, and the clocks of
        # max_duration, progress and plateaus stand.
        self.paused = False
        self.pause_began = 0.0                       # [s] simulated, when the current pause began
        self.pause_requested: Optional[bool] = None  # set by the callbacks, taken by the loop
        self.paused_s = 0.0                          # [s] simulated, in pauses so far
        self.pause_srv = rospy.Service('explore/pause', Trigger, lambda _: self.request_pause(True))
        self.resume_srv = rospy.Service('explore/resume', Trigger, lambda _: self.request_pause(False))
        rospy.Subscriber('explore/resume', Bool, lambda msg: self.request_pause(not msg.data))
        # The area to explore (frontier_exploration's polygon), map frame; None: everywhere.
        self.boundary: Optional[np.ndarray] = c.boundary
        self.outside_m = 0.0  # [m] of frontier left out by the boundary at the last cycle
        rospy.Subscriber('explore/boundary', PolygonStamped, self.on_boundary, queue_size=1)
        # Keep-out zones (move_base's keep-out filter's mask), map frame; None: none.
        self.keepout: Optional[Grid] = None
        self.keepout_m = 0.0  # [m] of frontier the zones took away at the last cycle
        self.keepout_topic = c.keepout_mask_topic
        if c.keepout_mask_topic:
            rospy.Subscriber(c.keepout_mask_topic, numpy_msg(OccupancyGrid), self.on_keepout, queue_size=1,
                             buff_size=2 ** 24)
        self.mates = {}  # name -> (ExplorerState, wall time received)
        self.team_pub = None
        if team_topic:
            self.team_pub = rospy.Publisher(team_topic, ExplorerState, queue_size=10)
            rospy.Subscriber(team_topic, ExplorerState, self.on_mate, queue_size=20)
            # Said every second besides each cycle, so that the base station (explore_team) can
            # tell a robot that is busy (backing out, waiting) from one whose link or host is down.
            rospy.Timer(rospy.Duration(1.0), self.heartbeat)
        self.told_pose = None  # the pose last told the team, once exploring
        self.ended = False

    def on_boundary(self, msg: PolygonStamped) -> None:
        """explore/boundary: the area to explore from now on; an empty polygon: everywhere."""
        frame = msg.header.frame_id.lstrip('/')
        if not msg.polygon.points:
            self.boundary = None
            rospy.loginfo('explore: boundary cleared: exploring everywhere')
            return
        if frame and frame != self.global_frame:
            rospy.logwarn('explore: a boundary on explore/boundary in frame "%s" ignored: it must be in %s'
                          % (frame, self.global_frame))
            return
        if len(msg.polygon.points) < 3:
            rospy.logwarn('explore: a boundary on explore/boundary with %d points ignored: a polygon needs 3'
                          % len(msg.polygon.points))
            return
        self.boundary = np.array([[p.x, p.y] for p in msg.polygon.points], float)
        rospy.loginfo('explore: exploring inside a boundary of %d points from explore/boundary' % len(self.boundary))

    def on_keepout(self, msg: OccupancyGrid) -> None:
        """The keep-out mask: its forbidden cells (100) are left unexplored."""
        frame = msg.header.frame_id.lstrip('/')
        if frame and frame != self.global_frame:
            rospy.logerr('explore: the keep-out mask on %s is in frame "%s", not %s: ignored'
                         % (rospy.resolve_name(self.keepout_topic), frame, self.global_frame))
            return
        mask = grid_of(msg)
        self.keepout = mask
        rospy.loginfo('explore: keep-out zones from %s: %.1f m^2 left unexplored'
                      % (rospy.resolve_name(self.keepout_topic), np.count_nonzero(mask.data >= 100) * mask.resolution ** 2))

    def request_pause(self, pause: bool) -> TriggerResponse:
        """explore/pause and explore/resume (services), explore/resume (std_msgs/Bool, explore_lite's:
        false pauses, true resumes). The exploring loop acts on it within a tenth of a second."""
        was = self.paused if self.pause_requested is None else self.pause_requested
        self.pause_requested = pause
        if self.start_time is None:
            what = 'not exploring yet; it will %s when it starts' % ('wait paused' if pause else 'go on')
        elif was == pause:
            what = 'already %s' % ('paused' if pause else 'exploring')
        else:
            what = 'pausing: no new goals, the current one cancelled' if pause else 'resuming'
        return TriggerResponse(success=True, message='explore: ' + what)

    def on_mate(self, msg: ExplorerState) -> None:
        if msg.robot != self.robot_name:
            self.mates[msg.robot] = msg

    def teammates(self) -> List[Teammate]:
        """The other explorers still exploring, as they last said within 10 s (simulated)."""
        now = rospy.Time.now()
        return [Teammate(m.robot, (m.position.x, m.position.y), (m.goal.x, m.goal.y) if m.has_goal else None)
                for m in list(self.mates.values())
                if not m.done and abs((now - m.header.stamp).to_sec()) < 10.0]

    def heartbeat(self, _event) -> None:
        if self.told_pose is not None and not self.ended:
            self.tell_team(self.told_pose)

    def tell_team(self, pose, done: bool = False) -> None:
        if self.team_pub is None:
            return
        if pose is not None:
            self.told_pose = pose
        msg = ExplorerState(robot=self.robot_name, done=done)
        msg.header.stamp, msg.header.frame_id = rospy.Time.now(), self.global_frame
        if pose is not None:
            msg.position = Point(pose[0], pose[1], 0.0)
        goal = self.state.goal
        if goal is not None and not done:
            msg.has_goal, msg.goal = True, Point(goal.goal[0], goal.goal[1], 0.0)
        self.team_pub.publish(msg)

    def on_map(self, msg: OccupancyGrid) -> None:
        with self.map_lock:  # the held map replaced in the order the followed map takes them
            self.map = self.followed.whole(msg, rospy.Time.now())
            taken = self.followed.stamp == msg.header.stamp  # else a stale latched map
            self.map_with_stamp = (self.map, self.followed.stamp)  # one assignment: read together
        if taken and self.start_time is not None:
            self.curve.append(((msg.header.stamp - self.start_time).to_sec(), explore_report.known_area(self.map)))

    def on_map_update(self, msg: OccupancyGridUpdate) -> None:
        """A window of the map replaced (a new Grid: the explorer's loop may hold the old one)."""
        with self.map_lock:
            m = self.followed.update(msg)
            if m is not None:
                self.map = m
                self.map_with_stamp = (self.map, msg.header.stamp)
        if m is None:  # not for the map held: kept for the next whole map
            return
        if self.start_time is not None:
            self.curve.append(((msg.header.stamp - self.start_time).to_sec(), explore_report.known_area(self.map)))

    def on_costmap(self, msg: OccupancyGrid) -> None:
        self.costmap = grid_of(msg)

    def on_scan(self, msg: LaserScan) -> None:
        self.scan = msg

    def on_contact(self, msg: Contact) -> None:
        if not msg.robot_at_fault:  # a person walked into the robot: the simulator logs it; not ours
            return
        if self.model_name and msg.model_name != self.model_name:
            return  # another robot of the team
        self.collisions += 1
        rospy.logwarn('explore: the robot touched %s at (%.2f, %.2f)',
                      'the world' if msg.other_kind in ('', 'world') else msg.other, msg.pose.x, msg.pose.y)

    def robot_pose(self) -> Optional[Tuple[float, float, float]]:
        try:
            t = self.tf.lookup_transform(self.global_frame, self.base_frame, rospy.Time(0),
                                         rospy.Duration(self.transform_tolerance))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(10.0, 'explore: no transform %s -> %s: %s' % (self.global_frame, self.base_frame, e))
            return None
        q = t.transform.rotation
        return t.transform.translation.x, t.transform.translation.y, quaternion_to_yaw(q.x, q.y, q.z, q.w)

    def map_in_world(self, start) -> Tuple[float, float, float]:
        """The map frame's pose in the world, for the report's ground truth: from the simulator's
        ground truth of the robot at the start (base_pose_ground_truth) and its pose in the map; the
        identity without a world or without ground truth (a real robot)."""
        if not self.world_name:
            return 0.0, 0.0, 0.0
        topic = rospy.resolve_name('base_pose_ground_truth')
        try:
            truth = rospy.wait_for_message(topic, Odometry, timeout=5.0)
        except (rospy.ROSException, rospy.ROSInterruptException):
            rospy.loginfo('explore: no ground truth on %s: the report takes the map frame as the world frame', topic)
            return 0.0, 0.0, 0.0
        p, q = truth.pose.pose.position, truth.pose.pose.orientation
        return compose2d((p.x, p.y, quaternion_to_yaw(q.x, q.y, q.z, q.w)), inverse2d(start))

    def truth_world(self):
        """The world file's shapes that meet this robot's body (from its URDF, robot_description),
        or None when there is no world file."""
        if not (self.world_name and os.path.isfile(self.world_name)):
            return None
        key = rospy.search_param('robot_description')
        world, warning = load_truth(self.world_name, rospy.get_param('/gazebo/map_unknown', 'solid'),
                                    rospy.get_param(key, '') if key else None, key or '')
        if warning:
            rospy.logwarn('explore: %s' % warning)
        return world

    def return_allowance(self, start) -> float:
        """[s] for the way back: return_timeout, or RETURN_S_PER_M per metre of the path to the start
        on the global costmap if that is longer (a building's far wing is minutes away)."""
        pose, costmap, m = self.robot_pose(), self.costmap, self.map
        if pose is None or costmap is None or m is None:
            return self.return_timeout
        rr, rc = costmap.cell_of(pose[0], pose[1])
        sr, sc = costmap.cell_of(start[0], start[1])
        if not (costmap.inside(rr, rc) and costmap.inside(sr, sc)):
            return self.return_timeout
        lengths = _core._path_lengths(passable(costmap, m).astype(np.uint8), int(rc), int(rr))
        path_m = lengths[sr, sc] * costmap.resolution if lengths[sr, sc] >= 0 else math.hypot(
            pose[0] - start[0], pose[1] - start[1])
        return max(self.return_timeout, RETURN_S_PER_M * path_m)

    def goals_failed(self) -> int:
        return sum(not reached for _, _, reached in self.goals)

    def clear_costmaps(self) -> None:
        """move_base's ~clear_costmaps, as its recoveries use it; failures are only logged."""
        try:
            rospy.ServiceProxy('move_base/clear_costmaps', Empty)()
        except (rospy.ServiceException, rospy.ROSException) as e:
            rospy.logwarn_throttle(30.0, 'explore: move_base/clear_costmaps failed: %s' % e)

    def record_path(self, pose=None) -> None:
        """Adds the robot's position to its path, every 0.5 s (ROS time) at most."""
        now = rospy.Time.now().to_sec()
        if now - self.path_time < 0.5 and now >= self.path_time:
            return
        pose = pose or self.robot_pose()
        if pose is not None:
            self.path.append(pose[:2])
            self.path_time = now

    def send(self, x: float, y: float, yaw: float) -> None:
        g = MoveBaseGoal()
        g.target_pose.header.frame_id = self.global_frame
        g.target_pose.header.stamp = rospy.Time.now()
        g.target_pose.pose = pose_msg(x, y, yaw)
        self.move_base.send_goal(g)

    def publish_markers(self, frontiers: List[Frontier], unranked: Sequence[np.ndarray] = ()) -> None:
        """The frontiers ranked (the best green, the others blue, each with its goal) and the cells
        of those not ranked this cycle (grey: too far to be among the best)."""
        if not self.visualize or self.marker_pub.get_num_connections() == 0:
            return  # thousands of cells to build and send: only for someone who looks (rviz)
        out = MarkerArray()
        clear = Marker(action=Marker.DELETEALL)
        clear.header.frame_id = self.global_frame
        out.markers.append(clear)
        now = rospy.Time.now()
        for i, f in enumerate(frontiers):
            colour = ColorRGBA(0.0, 0.9, 0.0, 1.0) if i == 0 else ColorRGBA(0.0, 0.3, 1.0, 0.8)
            cells = Marker(type=Marker.POINTS, action=Marker.ADD, ns='frontiers', id=2 * i)
            cells.header.frame_id, cells.header.stamp = self.global_frame, now
            cells.scale.x = cells.scale.y = self.map.resolution if self.map else 0.05
            cells.color = colour
            cells.pose.orientation.w = 1.0
            cells.points = [Point(x, y, 0.0) for x, y in f.cells]
            goal = Marker(type=Marker.SPHERE, action=Marker.ADD, ns='goals', id=2 * i + 1)
            goal.header.frame_id, goal.header.stamp = self.global_frame, now
            goal.pose = pose_msg(f.goal[0], f.goal[1], 0.0)
            goal.scale.x = goal.scale.y = goal.scale.z = 0.15
            goal.color = colour
            out.markers += [cells, goal]
        if self.boundary is not None:
            line = Marker(type=Marker.LINE_STRIP, action=Marker.ADD, ns='boundary', id=0)
            line.header.frame_id, line.header.stamp = self.global_frame, now
            line.scale.x = 0.05
            line.color = ColorRGBA(1.0, 0.5, 0.0, 1.0)
            line.pose.orientation.w = 1.0
            line.points = [Point(float(x), float(y), 0.0) for x, y in list(self.boundary) + [self.boundary[0]]]
            out.markers.append(line)
        if len(unranked):
            rest = Marker(type=Marker.POINTS, action=Marker.ADD, ns='frontiers_unranked', id=0)
            rest.header.frame_id, rest.header.stamp = self.global_frame, now
            rest.scale.x = rest.scale.y = self.map.resolution if self.map else 0.05
            rest.color = ColorRGBA(0.5, 0.5, 0.5, 0.8)
            rest.pose.orientation.w = 1.0
            rest.points = [Point(x, y, 0.0) for c in unranked for x, y in c]
            out.markers.append(rest)
        self.marker_pub.publish(out)

    def finish_goal(self, now: float) -> bool:
        """Takes in move_base's result for the current goal, if it has one; True if it failed."""
        if self.state.goal is None or self.move_base.simple_state != SimpleGoalState.DONE:
            return False
        gx, gy = self.state.goal.goal
        if self.move_base.get_state() == GoalStatus.SUCCEEDED:
            self.goals.append((gx, gy, True))
            self.state.reached(now, arrived=True)
            return False
        self.goals.append((gx, gy, False))
        text = self.move_base.get_goal_status_text()
        rospy.logwarn('explore: move_base gave up on (%.2f, %.2f): %s; blacklisted for %.0f s', gx, gy, text,
                      self.state.blacklist_timeout)
        self.state.fail(now, 'move_base: %s' % text)
        return True

    def missing(self, start) -> str:
        return ', '.join(what for what, missing in (
            ('the move_base action server on %s' % rospy.resolve_name('move_base'),
             not self.move_base.wait_for_server(rospy.Duration(0.01))),
            ('a map on %s' % rospy.resolve_name(self.map_topic), self.map is None),
            ('a costmap on %s' % rospy.resolve_name(self.costmap_topic), self.costmap is None),
            ('the robot pose (%s -> %s)' % (self.global_frame, self.base_frame), start is None)) if missing)

    def run(self) -> None:
        rospy.loginfo('explore: waiting for move_base, the map and the global costmap...')
        waited = time.monotonic()
        start = None
        checked = 0.0
        while not rospy.is_shutdown():
            if self.move_base.wait_for_server(rospy.Duration(0.5)):
                start = self.robot_pose()
                if self.map is not None and self.costmap is not None and start is not None:
                    break
            elapsed = time.monotonic() - waited
            if elapsed > self.startup_timeout:
                why = 'nothing to explore with after %.0f s (wall): no %s' % (elapsed, self.missing(start))
                rospy.logerr('explore: %s' % why)
                self.write_failure(why)
                return
            if elapsed > 20.0:
                rospy.logwarn_throttle(30.0, 'explore: still waiting (%.0f s) for %s' % (elapsed, self.missing(start)))
            if elapsed > checked + 5.0:
                checked = elapsed
                for sub in self.inputs:
                    sub.check()
            time.sleep(0.5)  # wall time: simulated time may not run yet
        if rospy.is_shutdown():
            return
        self.start_time = rospy.Time.now()
        wall0 = time.monotonic()
        self.cpu0 = time.process_time()  # the report's CPU while exploring: start-up and report apart
        rospy.loginfo('explore: started at (%.2f, %.2f)', start[0], start[1])
        self.world_from_map = self.map_in_world(start)
        try:
            outcome = self.explore(wall0)
        except Exception as e:  # a bug of ours: stop the robot and report it rather than die silently
            rospy.logerr('explore: internal error, the exploration ends here: %s\n%s' % (e, traceback.format_exc()))
            self.error = '%s: %s' % (type(e).__name__, e)
            self.cmd_pub.publish(Twist())
            outcome = 'error'
        if outcome is not None:
            self.finish(outcome, start, wall0)

    def explore(self, wall0: float) -> Optional[str]:
        """Sends frontier goals until the outcome is decided: 'complete', 'timeout' or 'stuck' (None
        on shutdown)."""
        next_print, empty_cycles, escapes_failed = 0.0, 0, 0
        boxed_since: Optional[float] = None
        while not rospy.is_shutdown():
            if self.pause_requested is not None and self.pause_requested != self.paused:
                self.set_paused(self.pause_requested)
            if self.paused:
                self.wait_paused()
                continue
            now = self.elapsed()
            if self.max_duration > 0 and now - self.paused_s >= self.max_duration:
                rospy.logwarn('explore: max_duration %.0f s reached with frontiers left; ending the exploration'
                              % self.max_duration)
                pose = self.robot_pose()
                if pose is not None and self.costmap is not None:
                    # every frontier left, ranked, for the report's list of those given up
                    m, m_stamp = self.map_with_stamp
                    self.frontiers(now, m, m_stamp, self.costmap, pose, self.state.avoid(now), everything=True)
                return 'timeout'
            pose = self.robot_pose()
            if pose is None:
                sim_sleep(self.period)
                continue
            self.record_path(pose)
            self.motion.update(now, pose[:2])
            if self.motion.still_for(now) == 0.0:
                escapes_failed = 0  # it moved: an earlier failed escape says nothing about here
            failed = self.finish_goal(now)
            goal = self.state.goal
            if self.state.stuck(now, pose[:2]):
                self.goals.append((goal.goal[0], goal.goal[1], False))
                rospy.logwarn('explore: no progress towards (%.2f, %.2f) for %.0f s; goal blacklisted for %.0f s'
                              % (goal.goal[0], goal.goal[1], self.state.progress_timeout, self.state.blacklist_timeout))
                self.move_base.cancel_goal()
                failed = True
            if failed and self.motion.still_for(now) >= self.state.progress_timeout:
                # Goals fail and the robot has not moved: move_base cannot turn or back it out.
                if self.escape(pose):
                    escapes_failed = 0
                else:
                    escapes_failed += 1
                    if escapes_failed >= 2:
                        return 'stuck'
                continue
            m, m_stamp = self.map_with_stamp
            # One costmap for the whole cycle: the callback may replace it with a larger one (the
            # SLAM map grew) between two uses, and a goal found on one is no cell of the other.
            costmap = self.costmap
            frontiers, waiting, stats = self.frontiers(now, m, m_stamp, costmap, pose, self.state.avoid(now))
            revisit = False
            if not frontiers and not waiting:
                # Nothing left but what lies near places already visited (see
                # ExploreState.avoid_for_good): a frontier there as large as a door (a room seen only
                # from its doorway, whose frontier came back when the map was corrected) counts now;
                # a smaller one (a nook behind furniture, seen from the floor as much as it can be)
                # is given up, with why.
                frontiers, waiting, stats = self.frontiers(now, m, m_stamp, costmap, pose,
                                                           self.state.avoid_for_good())
                revisit_size = REVISIT_SIZE_FACTOR * self.min_frontier_size
                for f in frontiers:
                    if f.size_m < revisit_size:
                        x, y = f.cells.mean(axis=0)
                        self.given_up.append(GivenUp(float(x), float(y), f.size_m, 'near places visited before and '
                                                     'smaller than %.1f m' % revisit_size))
                frontiers = [f for f in frontiers if f.size_m >= revisit_size]
                revisit = bool(frontiers)
            claimed = 0
            if self.team_pub is not None:
                mates = self.teammates()
                if self.state.goal is not None and yields_goal(self.state.goal.goal, self.robot_name, mates,
                                                               self.claim_radius):
                    rospy.loginfo('explore: (%.2f, %.2f) is also a teammate\'s goal; leaving it to them'
                                  % self.state.goal.goal)
                    self.state.goal = None
                    self.move_base.cancel_goal()
                frontiers, claimed = share_out(frontiers, mates, self.claim_radius, self.potential_scale)
            elif self.tour_frontiers >= 2 and 'passable' in stats:
                frontiers = tour_order(frontiers, stats['passable'], stats['costmap'], self.potential_scale,
                                       self.tour_frontiers)
            self.publish_markers(frontiers, stats.get('unranked', ()))
            self.plateau.update(now, explore_report.known_area(m), bool(frontiers) or self.state.goal is not None)
            new = self.state.choose(now, frontiers, pose[:2])
            self.tell_team(pose)
            if new is not None:
                yaw = math.atan2(new.goal[1] - pose[1], new.goal[0] - pose[0])
                self.send(new.goal[0], new.goal[1], yaw)
                rospy.loginfo('explore: goal (%.2f, %.2f), %.1f m away, frontier %.1f m (%.1f m^2 unknown beside it)%s; '
                              '%d frontiers; %s', new.goal[0], new.goal[1], new.path_m, new.size_m, new.unknown_m2,
                              ' (near a place visited before: nothing else is left)' if revisit else '',
                              len(frontiers), self.state.why)
            reachable_m2 = stats.get('reachable_m2', 0.0)
            if frontiers or self.state.goal is not None:
                empty_cycles, boxed_since = 0, None
            elif waiting or claimed:
                # Not done: frontiers wait out their blacklisting, or teammates are on their way to
                # them (one may fail and leave its frontier to this robot).
                rospy.loginfo_throttle(30.0, 'explore: %d frontier(s) blacklisted for now, %d left to teammates; '
                                       'waiting' % (waiting, claimed))
            elif stats.get('robot_outside'):
                # Not done: the robot stands beyond the global costmap, which grows with the map a
                # cycle or two later.
                rospy.loginfo_throttle(30.0, 'explore: the robot is outside the global costmap (it grows with the '
                                       'map); waiting')
            elif reachable_m2 < BOXED_IN_M2:
                # Not done: the robot is boxed in on its costmap (an obstacle seen beside it, a stale
                # costmap). Clearing the costmaps frees it if the obstacle is gone; if not within
                # progress_timeout, it backs out along its own path; if it cannot, it is stuck.
                if boxed_since is None:
                    # Usually an obstacle the laser saw beside the robot, gone after clearing: said
                    # as information; a robot still boxed in after progress_timeout is warned about.
                    boxed_since = now
                    rospy.loginfo('explore: the robot can reach only %.1f m^2 on the global costmap; clearing the '
                                  'costmaps' % reachable_m2)
                    self.clear_costmaps()
                elif now - boxed_since >= self.state.progress_timeout:
                    if not self.escape(pose):
                        rospy.logerr('explore: the robot is boxed in: it can reach %.2f m^2 and cannot back out'
                                     % reachable_m2)
                        return 'stuck'
                    boxed_since = None
            else:
                empty_cycles += 1  # twice in a row, so that one odd costmap does not end it
                if empty_cycles >= 2:
                    return 'complete'
            if now >= next_print:
                next_print = now + self.progress_period
                print('explore: %.1f m^2 known, %d frontiers, %d goals sent (%d failed), robot at (%.2f, %.2f), '
                      '%.0f s simulated in %.0f s wall'
                      % (explore_report.known_area(self.map), len(frontiers) + len(stats.get('unranked', ())),
                         self.state.goals_chosen,
                         self.goals_failed(), pose[0], pose[1], now, time.monotonic() - wall0), flush=True)
            self.wait_cycle()
        return None

    def set_paused(self, pause: bool) -> None:
        self.paused = pause
        now = self.elapsed()
        if pause:
            self.pause_began = now
            if self.state.goal is not None:
                self.move_base.cancel_goal()
                self.state.goal = None  # chosen anew on resuming: the map may have changed
            rospy.loginfo('explore: paused at %.0f s: no new goals until explore/resume' % now)
        else:
            self.paused_s += now - self.pause_began
            # the robot stood still on purpose: neither stuck nor on a plateau
            pose = self.robot_pose()
            if pose is not None:
                self.motion.reset(now, pose[:2])
            self.plateau.pause(now - self.pause_began)
            rospy.loginfo('explore: resumed at %.0f s after a pause of %.0f s' % (now, now - self.pause_began))

    def wait_paused(self) -> None:
        """One short wait while paused, the path still recorded."""
        self.record_path()
        sim_sleep(0.1)

    def frontiers(self, now: float, m: Grid, m_stamp, costmap: Grid, pose, avoid,
                  everything: bool = False) -> Tuple[List[Frontier], int, dict]:
        """(frontiers that may be sent now, best first; how many wait out a blacklisting; the
        ranking's stats), with the frontier cells near `avoid` left out; what is given up, and why,
        goes to self.given_up (the report's list). Only as many as the explorer uses are ranked
        (stats['unranked']: the cells of those left), unless `everything`."""
        stats = {}
        unreachable: List[GivenUp] = []
        map_time = (m_stamp - self.start_time).to_sec()
        judge = self.state.screener(now, map_time)
        # The best tour_frontiers that may be sent are what the explorer uses (all of them when
        # sharing with a team, which takes some away; all when `everything`, for the report).
        enough = 0 if self.team_pub is not None or everything else max(1, self.tour_frontiers)
        ranked = rank_frontiers(m, costmap, pose[:2], self.min_frontier_size, self.potential_scale,
                                self.gain_scale, avoid, self.state.blacklist_radius,
                                min_unknown_area=self.min_unknown_area, stats=stats,
                                avoid_goals=self.state.avoid_goals(now), unreachable=unreachable,
                                keep_goal=self.state.goal.goal if self.state.goal is not None else None,
                                min_unknown_beside=self.min_unknown_beside, gain_size_max=self.gain_size_max,
                                enough=enough, eligible=lambda f: judge(f) is ELIGIBLE, boundary=self.boundary,
                                keepout=self.keepout)
        self.outside_m = stats.get('outside_m', 0.0)
        self.keepout_m = stats.get('keepout_m', 0.0)
        frontiers, waiting, given_up = self.state.screen(now, ranked, map_time)
        self.given_up = given_up + unreachable
        return frontiers, waiting, stats

    def wait_cycle(self) -> None:
        """Until the next planning cycle: 1/planner_frequency, or sooner when move_base finishes the
        goal (the robot would otherwise stand at a reached goal for up to a whole period) or a pause
        or resume is asked for."""
        self.wait_for_goal(self.period, watch=self.state.goal is not None, pausable=True)

    def wait_for_goal(self, timeout: float, watch: bool = True, pausable: bool = False) -> bool:
        """Waits up to `timeout` [s, ROS time], recording the path; with `watch`, only until move_base
        has finished the goal, with `pausable` only until a pause or resume is asked for. True if
        move_base has finished (and `watch`)."""
        start = rospy.Time.now()
        end = start + rospy.Duration(timeout)
        while not rospy.is_shutdown() and start <= rospy.Time.now() < end:
            if watch and self.move_base.simple_state == SimpleGoalState.DONE:
                return True
            if pausable and self.pause_requested is not None and self.pause_requested != self.paused:
                return False  # paused or resumed: the exploring loop acts on it now
            self.record_path()
            sim_sleep(min(0.25, timeout))
        return watch and self.move_base.simple_state == SimpleGoalState.DONE

    def elapsed(self) -> float:
        """[s] simulated (ROS) time since the exploration started."""
        return (rospy.Time.now() - self.start_time).to_sec()

    def escape(self, pose) -> bool:
        """Backs the robot out along its own recent path (it drove in, so that way was free),
        driving by cmd_vel and checking the laser, not the costmap that has it boxed in; tries points
        of the path at escape_distance, 1.6 and 0.6 times it. True if it got to one of them."""
        self.move_base.cancel_goal()
        targets = []
        for k in (1.0, 1.6, 0.6):
            t = backtrack_target(self.path, pose[:2], k * self.escape_distance)
            if t is not None and t not in targets:
                targets.append(t)
        if not targets:
            rospy.logerr('explore: the robot at (%.2f, %.2f) cannot move and has no path of its own to back out along'
                         % pose[:2])
            return False
        rospy.logwarn('explore: the robot at (%.2f, %.2f) made no progress for %.0f s and move_base cannot move it; '
                      'backing out along its own path' % (pose[0], pose[1], self.motion.still_for(self.elapsed())))
        self.scan = None
        scan_sub = rospy.Subscriber(self.scan_topic, numpy_msg(LaserScan), self.on_scan, queue_size=1)
        try:
            for target in targets:
                ok, why = self.drive_to(target)
                self.cmd_pub.publish(Twist())
                if ok:
                    rospy.logwarn('explore: backed out to (%.2f, %.2f); exploring on' % target)
                    self.clear_costmaps()
                    self.motion.reset(self.elapsed(), target)
                    return True
                rospy.logwarn('explore: could not back out to (%.2f, %.2f): %s' % (target[0], target[1], why))
            return False
        finally:
            scan_sub.unregister()

    def drive_to(self, target: Tuple[float, float]) -> Tuple[bool, str]:
        """Drives straight for `target` (map frame), forwards or backwards, whichever faces it."""
        t_end = self.elapsed() + self.escape_timeout
        while not rospy.is_shutdown() and self.elapsed() < t_end:
            pose = self.robot_pose()
            if pose is None:
                sim_sleep(0.1)
                continue
            self.record_path(pose)
            points = self.scan_points()
            if points is None:  # never drive blind
                rospy.logwarn_throttle(5.0, 'explore: waiting for a scan on %s to back out safely'
                                       % rospy.resolve_name(self.scan_topic))
                sim_sleep(0.1)
                continue
            cmd, why = escape_command(pose, target, points, self.robot_radius, self.escape_speed)
            if cmd is None:
                return why == 'arrived', why
            self.cmd_pub.publish(Twist(linear=Vector3(cmd[0], 0.0, 0.0), angular=Vector3(0.0, 0.0, cmd[1])))
            sim_sleep(0.1)
        return False, 'did not get there within %.0f s' % self.escape_timeout

    def scan_points(self) -> Optional[np.ndarray]:
        """(N, 2) [m] the latest scan's returns in the robot's base frame (None if none yet)."""
        msg = self.scan
        if msg is None:
            return None
        try:
            t = self.tf.lookup_transform(self.base_frame, msg.header.frame_id, rospy.Time(0), rospy.Duration(0.1))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(5.0, 'explore: no transform %s -> %s for the scan: %s'
                                   % (msg.header.frame_id, self.base_frame, e))
            return None
        r = np.asarray(msg.ranges, float)
        a = msg.angle_min + msg.angle_increment * np.arange(len(r))
        ok = np.isfinite(r) & (r >= msg.range_min) & (r <= msg.range_max)
        q = t.transform.rotation
        yaw = quaternion_to_yaw(q.x, q.y, q.z, q.w)
        x = t.transform.translation.x + r[ok] * np.cos(a[ok] + yaw)
        y = t.transform.translation.y + r[ok] * np.sin(a[ok] + yaw)
        return np.column_stack([x, y])

    def write_failure(self, why: str) -> None:
        """The report of a run that could not start (outcome not_started), so that whoever waits for
        it (run_exploration, a test) learns why instead of waiting out its own limit."""
        if self.report_dir:
            explore_report.write_figures(os.path.abspath(self.report_dir), {'outcome': 'not_started', 'why': why})
        self.done_pub.publish(Bool(True))

    def finish(self, outcome: str, start, wall0: float) -> None:
        t_explored = self.elapsed()
        cpu_exploring = time.process_time() - self.cpu0  # all the node's threads
        self.move_base.cancel_goal()
        if outcome == 'complete':
            rospy.loginfo('explore: no reachable frontier left after %.0f s; exploration complete', t_explored)
        if outcome == 'error':
            pass  # no return: whatever failed may fail again
        elif outcome == 'stuck':
            self.cmd_pub.publish(Twist())
            rospy.logerr('explore: the robot is stuck at %s; the exploration ends here' % (self.robot_pose(),))
        elif self.return_to_start:
            allowed = self.return_allowance(start)
            rospy.loginfo('explore: returning to the start pose (%.2f, %.2f), %.0f s allowed', start[0], start[1], allowed)
            self.send(*start)
            if not self.wait_for_goal(allowed):
                rospy.logwarn('explore: not back at the start after %.0f s; stopping there' % allowed)
                self.move_base.cancel_goal()
            pose = self.robot_pose()
            if pose is not None:
                self.path.append(pose[:2])
        distance = float(np.sum(np.hypot(*np.diff(np.array(self.path), axis=0).T))) if len(self.path) > 1 else 0.0
        figures = {
            'outcome': outcome,
            'exploration_time_s': round(t_explored, 1),
            'total_time_s': round(self.elapsed(), 1),
            'wall_time_s': round(time.monotonic() - wall0, 1),
            'distance_m': round(distance, 2),
            'goals_sent': self.state.goals_chosen,
            'goals_failed': self.goals_failed(),
            'collisions': self.collisions,
            'paused_s': round(self.paused_s, 1),
            'boundary': None if self.boundary is None else [[round(float(x), 3), round(float(y), 3)]
                                                            for x, y in self.boundary],
            'frontier_outside_boundary_m': round(self.outside_m, 2),
            'keepout_m2': (0.0 if self.keepout is None else
                           round(float(np.count_nonzero(self.keepout.data >= 100)) * self.keepout.resolution ** 2, 2)),
            'frontier_in_keepout_m': round(self.keepout_m, 2),
            'cpu_s_per_s_exploring': round(cpu_exploring / max(t_explored, 1e-6), 4),
            'longest_plateau_s': round(self.plateau.longest, 1),
            'longest_plateau_at_s': round(self.plateau.longest_at, 1),
            'given_up': [g.as_dict() for g in self.given_up],
        }
        if self.error:
            figures['error'] = self.error
        if self.report_dir and self.map is not None:
            world, rooms = self.truth_world(), ()
            if world is not None:
                rooms_file = rooms_file_of(self.world_name)
                if os.path.isfile(rooms_file):
                    try:
                        rooms = load_rooms(rooms_file)
                    except ValueError as e:
                        rospy.logwarn('explore: no coverage per room: %s' % e)
            figures = explore_report.write_report(os.path.abspath(self.report_dir), self.map, self.path, self.goals,
                                                  self.curve, figures, world, start[:2], self.robot_radius, rooms,
                                                  self.world_from_map, self.boundary, self.keepout)
            print('explore: report in %s (map.pgm, map.yaml, map.png, area.png, report.json)'
                  % os.path.abspath(self.report_dir), flush=True)
        for k, v in figures.items():
            if k not in ('given_up', 'room_coverage'):
                print('  %-28s %s' % (k, v), flush=True)
        for name, share in figures.get('room_coverage', {}).items():
            print('  room %-23s %.1f%% of its floor mapped' % (name, 100 * share), flush=True)
        for g in figures['given_up']:
            print('  given up: (%.2f, %.2f), %.1f m: %s' % (g['x'], g['y'], g['size_m'], g['why']), flush=True)
        rospy.loginfo('explore: exploration ended (%s): %s', outcome, figures)
        self.ended = True
        self.tell_team(self.robot_pose(), done=True)
        self.done_pub.publish(Bool(True))  # last, so that the report is on disk when it says so


def main() -> None:
    rospy.init_node('explore')
    node = Explore()
    try:
        node.run()
    except rospy.ROSInterruptException:
        return  # shut down mid-exploration (roslaunch ended): not a crash, no traceback
    if node.shutdown_when_done or rospy.is_shutdown():
        return
    rospy.spin()
