"""random_navigation.py of the exploration tutorial: move_base goals to named points in random order,
round after round, with the success rate, running time and distance in the log.

Faithful to the tutorial's script (its nine points p1..p9, ~rest_time, the goal-state names, 300 s per
goal, the log lines, a shutdown that cancels the goal and stops the robot), with its bugs fixed:
- `random.sample()` over a dict fails in Python 3: the names are shuffled as a list;
- the "make sure we have an initial position" loop compared a stamp with "" and never waited: it
  now waits for the robot's pose in the goal frame (SLAM's map -> base_footprint), and that pose is
  where the first distance is measured from;
- the initial-pose callback had no subscriber: `initialpose` (rviz's 2D Pose Estimate) now updates
  where the next distance is measured from, as the tutorial's "Updating current pose." intended;
- the points' quaternions are not unit length: each is normalized once, with a warning;
- `trunc()` broke on numbers printed in exponent form: it truncates arithmetically;
- a round whose first point repeats the last one skipped it, so that round had eight points: the
  repeated point is swapped later in the round instead, so every round visits every point.

Parameters (private): rest_time (2 s), locations_file ('' = the tutorial's table; see
config/wall_locations.yaml for the format), max_goals (0 = forever), max_duration (0 = forever, s
of ROS time), goal_timeout (300 s), seed (-1 = random), frame_id ('map'), base_frame
('base_footprint'), server_timeout (60 s of wall time), order (random, or sequence: a patrol in the
file's order) and rounds (0 = forever). With a limit it prints a summary and exits 0.

Beyond the tutorial: move_base killed mid-goal (and respawned) is noticed, waited for and the goal
sent again (pursue()), so a soak's count goes on instead of waiting out goal_timeout; a goal that
move_base aborts as blocked (occupied: a person passing over the point; no valid plan: a person in
a door on the way) is sent again after BLOCKED_WAIT s, at most BLOCKED_RETRIES times, with a warning.
"""
import math
import os
import random
import sys
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import rospy
import tf2_ros
import yaml
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import Point, Pose, PoseStamped, PoseWithCovarianceStamped, Quaternion, Twist, Vector3
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker

from mbot_slam_navigation.lazy_tf import LazyTransformBuffer
from mbot_slam_navigation.nav.action_client import SimpleActionClient
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.transforms import check_planar_quaternion, yaw_to_quaternion

SERVER_SILENCE = 5.0  # [s] of ROS time without move_base's action status (5 Hz) before it counts as gone
MAX_RESENDS = 2       # times a goal is sent again after move_base lost it
BLOCKED_WAIT = 10.0  # [s] of ROS time before a goal move_base aborted as blocked is sent again
BLOCKED_RETRIES = 2
# move_base's abort texts for a way blocked, maybe for a moment (people walk on): the goal is in an
# obstacle, or no plan was found even after the recoveries (a person resting in a door). Soaks lost
# 2-3 goals in 100 to people in doors, each a goal the robot would have reached seconds later.
# Checked in this order: an occupied goal's abort also begins 'Failed to find a valid plan'.
BLOCKED_REASONS = {'goal occupied': 'occupied', 'Failed to find a valid plan': 'without a plan'}

# actionlib_msgs/GoalStatus's states, in the order of their numbers (the tutorial's goal_states).
GOAL_STATES = ['PENDING', 'ACTIVE', 'PREEMPTED', 'SUCCEEDED', 'ABORTED', 'REJECTED', 'PREEMPTING', 'RECALLING',
               'RECALLED', 'LOST']


@dataclass
class Location:
    name: str
    room: str
    x: float                      # [m] in the goal frame (map)
    y: float
    orientation: Tuple[float, float, float, float]  # unit quaternion (x, y, z, w)
    note: str = ''                # why the orientation was changed, if it was


# The tutorial's table, verbatim (x, y, quaternion x, y, z, w), with the rooms its text names.
TUTORIAL_LOCATIONS = [
    ('p1', 'kitchen', 3.057, -4.795, (0.000, 0.000, 0.000, 0.168)),
    ('p2', 'dining room', 2.495, -2.381, (0.000, 0.000, 0.063, 0.347)),
    ('p3', 'bathroom', 3.240, -0.014, (0.000, 0.000, 0.946, -2.675)),
    ('p4', 'second bedroom', 2.336, 2.304, (0.000, 0.000, 0.139, -0.084)),
    ('p5', 'study', -0.831, 2.264, (0.000, 0.000, 0.919, -0.433)),
    ('p6', 'master bedroom, point 1', -3.523, 1.825, (0.000, 0.000, 0.627, 2.071)),
    ('p7', 'master bedroom, point 2', -4.002, 1.644, (0.000, 0.000, 0.139, -1.119)),
    ('p8', 'balcony, point 1', -6.420, -2.611, (0.000, 0.000, 0.919, -1.839)),
    ('p9', 'balcony, point 2', -6.420, -1.372, (0.000, 0.000, 0.627, 1.440)),
]


class LocationsError(ValueError):
    """A locations table that cannot be used; the message names the file and the key."""

    def __init__(self, path: str, key: str, message: str):
        self.path, self.key = path, key
        super().__init__("%s: key '%s': %s" % (path, key, message))


def make_location(name: str, room: str, x: float, y: float, quaternion: Sequence[float], where: str) -> Location:
    """A Location with a unit quaternion; raises LocationsError(where, name...) for an unusable one."""
    yaw, note = check_planar_quaternion(quaternion, "%s's orientation" % name)
    if yaw is None:
        raise LocationsError(where, name + '.orientation', note)
    return Location(name, room, float(x), float(y), yaw_to_quaternion(yaw), note)


def tutorial_locations() -> List[Location]:
    return [make_location(n, room, x, y, q, 'the built-in table') for n, room, x, y, q in TUTORIAL_LOCATIONS]


def _numbers(path: str, key: str, value, lengths: Tuple[int, ...], what: str) -> List[float]:
    if (not isinstance(value, (list, tuple)) or len(value) not in lengths
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
        raise LocationsError(path, key, 'must be %s, got %r' % (what, value))
    return [float(v) for v in value]


def load_locations(path: str) -> List[Location]:
    """The points of a locations YAML file, in file order. The file maps each name to
    `{room: TEXT, position: [x, y] or [x, y, z], orientation: [x, y, z, w]}` or `{..., yaw: RAD}`
    (metres and radians in the goal frame). Raises LocationsError naming the file and key."""
    try:
        with open(path) as f:
            doc = yaml.safe_load(f)
    except OSError as e:
        raise LocationsError(path, '', 'cannot read the file: %s' % e.strerror) from e
    except yaml.YAMLError as e:
        raise LocationsError(path, '', 'not valid YAML: %s' % e) from e
    if not isinstance(doc, dict) or not doc:
        raise LocationsError(path, '', 'must map point names to {position, orientation or yaw}, got %r' % (doc,))
    out = []
    for name, spec in doc.items():
        name = str(name)
        if not isinstance(spec, dict):
            raise LocationsError(path, name, 'must be a mapping with position and orientation or yaw, got %r' % (spec,))
        unknown = set(spec) - {'room', 'position', 'orientation', 'yaw'}
        if unknown:
            raise LocationsError(path, '%s.%s' % (name, sorted(unknown)[0]),
                                 'unknown key (known: room, position, orientation, yaw)')
        if 'position' not in spec:
            raise LocationsError(path, name + '.position', 'missing')
        pos = _numbers(path, name + '.position', spec['position'], (2, 3), '[x, y] or [x, y, z] in metres')
        if ('orientation' in spec) == ('yaw' in spec):
            raise LocationsError(path, name, 'give exactly one of orientation [x, y, z, w] and yaw [rad]')
        if 'yaw' in spec:
            q = yaw_to_quaternion(_numbers(path, name + '.yaw', [spec['yaw']], (1,), 'a number of radians')[0])
        else:
            q = _numbers(path, name + '.orientation', spec['orientation'], (4,), 'a quaternion [x, y, z, w]')
        out.append(make_location(name, str(spec.get('room', '')), pos[0], pos[1], q, path))
    return out


def trunc(f: float, n: int) -> float:
    """f cut (towards zero) to n decimals: the tutorial's helper, which sliced str(f) and broke on
    numbers that print in exponent form."""
    scale = 10 ** n
    return math.trunc(f * scale) / scale


def next_round(rng: random.Random, names: Sequence[str], last: str) -> List[str]:
    """A random order of all the names that does not start with `last` (no goal twice in a row)."""
    order = list(names)
    rng.shuffle(order)
    if len(order) > 1 and order[0] == last:
        k = rng.randrange(1, len(order))
        order[0], order[k] = order[k], order[0]
    return order


@dataclass
class Tally:
    """What the tutorial logs after every goal, and the summary at the end."""
    distance: float = 0.0             # [m] straight lines to the goals reached, as the tutorial counts
    outcomes: Dict[str, List[str]] = field(default_factory=dict)  # location -> state names

    @property
    def goals(self) -> int:
        return sum(len(states) for states in self.outcomes.values())

    @property
    def successes(self) -> int:
        return sum(s == 'SUCCEEDED' for states in self.outcomes.values() for s in states)

    def record(self, location: str, state: str, distance: float) -> None:
        self.outcomes.setdefault(location, []).append(state)
        if state == 'SUCCEEDED':
            self.distance += distance

    def success_line(self) -> str:
        rate = 100 * self.successes // self.goals if self.goals else 0
        return 'Success so far: %d/%d = %d%%' % (self.successes, self.goals, rate)

    def time_line(self, running_time_s: float) -> str:
        return 'Running time: %s min Distance: %s m' % (trunc(running_time_s / 60.0, 1), trunc(self.distance, 1))

    def summary(self, running_time_s: float, locations: Sequence[Location]) -> str:
        lines = ['Random navigation summary: %d goals, %d succeeded (%.1f%%), %.1f min, %.1f m'
                 % (self.goals, self.successes, 100.0 * self.successes / self.goals if self.goals else 0.0,
                    running_time_s / 60.0, self.distance)]
        for loc in locations:
            states = self.outcomes.get(loc.name, [])
            reached = sum(s == 'SUCCEEDED' for s in states)
            failed = ', '.join(sorted(set(s for s in states if s != 'SUCCEEDED')))
            lines.append('  %s %-28s %d/%d%s' % (loc.name, '(%s)' % loc.room if loc.room else '', reached, len(states),
                                                 '  failed: ' + failed if failed else ''))
        return '\n'.join(lines)


def read_parameters(r: ParamReader) -> dict:
    """The node's parameters (the tutorial's script has none; all are ours), checked."""
    c = {
        'rest_time': r.number('rest_time', 2.0, '[s] pause at each goal, as the tutorial', minimum=0.0),
        'max_goals': r.integer('max_goals', 0, 'stop after this many goals (0: never, as the tutorial)', minimum=0),
        'max_duration': r.number('max_duration', 0.0, '[s] stop after this much time (0: never)', minimum=0.0),
        'goal_timeout': r.number('goal_timeout', 300.0, '[s] a goal not reached in this time is cancelled',
                                 positive=True),
        'server_timeout': r.number('server_timeout', 60.0, '[s] wait for the move_base action server',
                                   positive=True),
        'frame_id': r.frame('frame_id', 'map', "the goals' frame"),
        'base_frame': r.frame('base_frame', 'base_footprint', "the robot's base frame (distance travelled)"),
        'seed': r.integer('seed', -1, "the random order's seed (-1: a different order each run)"),
        'locations_file': r.string('locations_file', '',
                                   "a YAML of named poses ('': the tutorial's nine places in the home)"),
        'order': r.string('order', 'random', "random (the tutorial's: each round in a new order) or sequence (a "
                          "patrol: the file's order, round after round)"),
        'rounds': r.integer('rounds', 0, 'stop after this many rounds through every point (0: never)', minimum=0),
    }
    if c['order'] not in ('random', 'sequence'):
        raise ParamError("parameter %s must be 'random' or 'sequence', got '%s'" % (r.where('order'), c['order']))
    return c


def next_marker(pose: PoseStamped, label: str) -> Marker:
    """The point being driven to, for rviz: a green arrow (0.5 m) at `pose`, labelled in its text."""
    m = Marker(type=Marker.ARROW, action=Marker.ADD, ns='next_point', id=0)
    m.header = pose.header
    m.pose = pose.pose
    m.scale = Vector3(0.5, 0.08, 0.08)
    m.color = ColorRGBA(0.1, 0.8, 0.2, 1.0)
    m.text = label
    return m


class GoalSender:
    """Sends one move_base goal at a time and sees it through move_base's faults (pursue). Users
    set move_base (a SimpleActionClient), goal_timeout and server_timeout [s], and goal(loc)."""
    log_name = 'random_navigation'

    def stop_requested(self) -> bool:
        """True when the goal being pursued is to be given up (a preempted waypoint action)."""
        return False

    def server_silence(self) -> float:
        """[s] of ROS time since move_base's last action status (inf before the first)."""
        last = self.move_base.action_client.last_status_msg
        return (rospy.Time.now() - last.header.stamp).to_sec() if last is not None else float('inf')

    def pursue(self, loc: Location) -> Optional[str]:
        """Sends the goal and waits for its end (goal_timeout); the state's name, or None at shutdown.

        move_base killed mid-goal (and respawned by roslaunch) is noticed two ways: its status
        stops (SERVER_SILENCE s), or the new process's status does not know the goal (actionlib
        calls it LOST). Either way the same goal is sent again once move_base answers, at most
        MAX_RESENDS times, so the count goes on; if it does not come back within server_timeout the
        goal counts as LOST."""
        deadline = rospy.Time.now() + rospy.Duration(self.goal_timeout)
        resends = blocked = 0
        self.move_base.send_goal(self.goal(loc))
        while not rospy.is_shutdown():
            if self.stop_requested():
                self.move_base.cancel_goal()
                return 'PREEMPTED'
            if self.move_base.wait_for_result(rospy.Duration(1.0)):
                code = self.move_base.get_state()
                text = self.move_base.get_goal_status_text()
                how = next((h for reason, h in BLOCKED_REASONS.items() if reason in text), None)
                if (code == GoalStatus.ABORTED and how and blocked < BLOCKED_RETRIES
                        and rospy.Time.now() + rospy.Duration(BLOCKED_WAIT) < deadline):
                    blocked += 1
                    rospy.logwarn(self.log_name + ': move_base aborted the goal to %s as %s (%s); waiting %g s '
                                  'for the way to clear (a person passing?), then sending it again (%d of %d)',
                                  loc.name, how, text, BLOCKED_WAIT, blocked, BLOCKED_RETRIES)
                    try:
                        rospy.sleep(BLOCKED_WAIT)
                    except rospy.ROSTimeMovedBackwardsException:
                        pass
                    except rospy.ROSInterruptException:
                        return None
                    self.move_base.send_goal(self.goal(loc))
                    continue
                if code != GoalStatus.LOST or resends >= MAX_RESENDS:
                    return GOAL_STATES[code] if 0 <= code < len(GOAL_STATES) else str(code)
                why = 'lost the goal (it was restarted?)'
            elif rospy.Time.now() > deadline:
                self.move_base.cancel_goal()
                return 'TIMED_OUT'
            elif self.server_silence() > SERVER_SILENCE:
                why = 'has sent no status for %.0f s (it died or hangs)' % self.server_silence()
            else:
                continue
            if resends >= MAX_RESENDS:
                return 'LOST'
            rospy.logwarn(self.log_name + ': move_base (%s) %s during the goal to %s; waiting up to %g s '
                          '(server_timeout) for it to answer, then sending the goal again',
                          rospy.resolve_name('move_base'), why, loc.name, self.server_timeout)
            if not self.move_base.wait_for_server(rospy.Duration(self.server_timeout)):
                if rospy.is_shutdown():
                    return None
                rospy.logerr(self.log_name + ': move_base did not come back within %g s; the goal to %s counts '
                             'as LOST', self.server_timeout, loc.name)
                return 'LOST'
            answer_by = rospy.Time.now() + rospy.Duration(self.server_timeout)
            while self.server_silence() > SERVER_SILENCE and rospy.Time.now() < answer_by:
                try:
                    rospy.sleep(0.2)  # connected: wait for the new process's first status
                except rospy.ROSTimeMovedBackwardsException:
                    answer_by = rospy.Time.now() + rospy.Duration(self.server_timeout)  # a reset: wait afresh
                except rospy.ROSInterruptException:
                    return None
            resends += 1
            rospy.loginfo(self.log_name + ': move_base answers again; sending the goal to %s again', loc.name)
            self.move_base.send_goal(self.goal(loc))
            deadline = rospy.Time.now() + rospy.Duration(self.goal_timeout)
        return None



class RandomNavigation(GoalSender):
    """The node (the tutorial's NavTest): run() sends the goals and returns the exit code."""

    def __init__(self):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        c = read_parameters(r)
        r.report_unknown()
        self.rest_time, self.max_goals, self.max_duration = c['rest_time'], c['max_goals'], c['max_duration']
        self.goal_timeout, self.server_timeout = c['goal_timeout'], c['server_timeout']
        self.frame_id, self.base_frame = c['frame_id'], c['base_frame']
        seed, locations_file = c['seed'], c['locations_file']
        self.order, self.rounds = c['order'], c['rounds']
        self.rounds_done = 0
        self.locations = load_locations(os.path.expanduser(locations_file)) if locations_file else tutorial_locations()
        for loc in self.locations:
            if loc.note:
                rospy.logwarn('random_navigation: %s', loc.note)
        self.rng = random.Random(None if seed < 0 else seed)

        self.cmd_vel_pub = rospy.Publisher('cmd_vel', Twist, queue_size=5)
        self.marker_pub = rospy.Publisher('~next_point', Marker, queue_size=1, latch=True)
        self.move_base = SimpleActionClient('move_base', MoveBaseAction)
        # /tf read lazily: only the pose lookups (a few a second) deserialize it; a
        # TransformListener would deserialize all 40-odd messages a simulated second
        self.tf = LazyTransformBuffer()
        self.new_pose: Optional[Tuple[float, float]] = None
        rospy.Subscriber('initialpose', PoseWithCovarianceStamped, self.update_initial_pose, queue_size=1)
        self.goal_active = False
        self.tally = Tally()
        self.start_time = None

    def update_initial_pose(self, msg) -> None:
        self.new_pose = (msg.pose.pose.position.x, msg.pose.pose.position.y)

    def robot_position(self, timeout: float) -> Optional[Tuple[float, float]]:
        """Where the robot is in the goal frame (from tf), or None when tf has no answer in time."""
        try:
            t = self.tf.lookup_transform(self.frame_id, self.base_frame, rospy.Time(0),
                                         rospy.Duration(timeout))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn('random_navigation: no transform %s -> %s yet: %s', self.frame_id, self.base_frame, e)
            return None
        return t.transform.translation.x, t.transform.translation.y

    def goal(self, loc: Location):
        g = MoveBaseGoal()
        g.target_pose.pose = Pose(Point(loc.x, loc.y, 0.0), Quaternion(*loc.orientation))
        g.target_pose.header.frame_id = self.frame_id
        g.target_pose.header.stamp = rospy.Time.now()
        return g

    def limit_reached(self) -> bool:
        if self.max_goals and self.tally.goals >= self.max_goals:
            return True
        if self.rounds and self.rounds_done >= self.rounds:
            return True
        return bool(self.max_duration) and self.running_time() >= self.max_duration

    def running_time(self) -> float:
        return (rospy.Time.now() - self.start_time).to_sec()

    def run(self) -> int:
        rospy.loginfo('Waiting for move_base action server...')
        if not self.move_base.wait_for_server(rospy.Duration(self.server_timeout)):
            if rospy.is_shutdown():
                return 0
            rospy.logerr('random_navigation: no move_base action server on %s after %g s; is move_base running? '
                         '(roslaunch mbot_slam_navigation robot_gazebo_navigation_move.launch)',
                         rospy.resolve_name('move_base'), self.server_timeout)
            return 1
        rospy.loginfo('Connected to move base server')

        # Make sure there is an initial position: the robot's pose in the goal frame.
        position = None
        while position is None and not rospy.is_shutdown():
            position = self.robot_position(5.0)
        if rospy.is_shutdown():
            return 0
        by_name = {loc.name: loc for loc in self.locations}
        names = [loc.name for loc in self.locations]
        rospy.loginfo('Starting navigation test: %d locations in %s: %s', len(names), self.frame_id, ' '.join(
            '%s (%s)' % (loc.name, loc.room) if loc.room else loc.name for loc in self.locations))
        self.start_time = rospy.Time.now()
        sequence, i, last = [], len(names), ''
        while not rospy.is_shutdown() and not self.limit_reached():
            if i == len(names):  # all visited: a new round, in a new random order or the file's
                sequence, i = (next_round(self.rng, names, last) if self.order == 'random' else list(names)), 0
                rospy.loginfo('Round %d%s', self.rounds_done + 1, ' of %d' % self.rounds if self.rounds else '')
            loc = by_name[sequence[i]]
            if self.new_pose is not None:  # a 2D Pose Estimate since the last goal
                rospy.loginfo('Updating current pose.')
                position, self.new_pose = self.new_pose, None
            distance = math.hypot(loc.x - position[0], loc.y - position[1])
            i += 1
            rospy.loginfo('Going to: %s%s', loc.name, ' (%s)' % loc.room if loc.room else '')
            self.marker_pub.publish(next_marker(self.goal(loc).target_pose, loc.name + (' (%s)' % loc.room
                                                                                        if loc.room else '')))
            self.goal_active = True
            state = self.pursue(loc)
            if state is None:
                break  # the shutdown hook cancels the goal; this one is not counted
            if state == 'TIMED_OUT':
                rospy.loginfo('Timed out achieving goal')
            elif state == 'SUCCEEDED':
                rospy.loginfo('Goal succeeded!')
                rospy.loginfo('State:' + str(GoalStatus.SUCCEEDED))
            else:
                rospy.loginfo('Goal failed with error code: ' + state)
            self.goal_active = False
            if state not in ('SUCCEEDED', 'TIMED_OUT'):
                # skipped with the reason (move_base's), the patrol goes on to the next point
                rospy.logwarn('random_navigation: %s skipped: %s', loc.name,
                              self.move_base.get_goal_status_text() or state)
            self.tally.record(loc.name, state, distance)
            if i == len(names):
                self.rounds_done += 1
            # Measured from where the robot was meant to be, as the tutorial does.
            position, last = (loc.x, loc.y), loc.name
            rospy.loginfo(self.tally.success_line())
            rospy.loginfo(self.tally.time_line(self.running_time()))
            if not self.limit_reached():
                try:
                    rospy.sleep(self.rest_time)
                except rospy.ROSTimeMovedBackwardsException:
                    rospy.logwarn('random_navigation: the clock went back (the simulation was reset?); going on')
                except rospy.ROSInterruptException:
                    break
        if self.start_time is not None and not rospy.is_shutdown():
            self.stop_robot()
        if self.start_time is not None:
            rospy.loginfo(self.tally.summary(self.running_time(), self.locations))
        return 0

    def stop_robot(self) -> None:
        self.cmd_vel_pub.publish(Twist())

    def shutdown(self) -> None:
        """Ctrl-C: cancel the goal and stop the robot (wall-clock waits: ROS time may have stopped)."""
        rospy.loginfo('Stopping the robot...')
        if self.goal_active:
            self.move_base.cancel_goal()
            time.sleep(0.5)
        self.stop_robot()
        time.sleep(0.5)


def main() -> None:
    rospy.init_node('random_navigation', anonymous=True)
    try:
        node = RandomNavigation()
    except (ParamError, LocationsError) as e:
        rospy.logfatal('random_navigation: %s', e)
        sys.exit(2)
    rospy.on_shutdown(node.shutdown)
    code = node.run()
    rospy.loginfo('Random navigation finished.')
    rospy.signal_shutdown('random navigation finished')
    sys.exit(code)
