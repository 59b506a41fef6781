"""gazebo_sim: the ROS face of the 2D simulator (stands in for gzserver + gazebo_ros plugins).

Parameters (private): world_name (SDF file or map_server YAML), map_unknown (solid), real_time_factor (1.0; 0 = as fast as possible;
'auto' = as fast as the nodes that report on /sim_heartbeat keep up, see sim/pacing.py),
min_real_time_factor (0.25) and max_real_time_factor (100) for auto, max_lag (0.15 simulated s:
the lag of the slowest node that auto aims below; defaults in sim/pacing.py), max_hold (0.1 wall s:
under auto, the longest the clock waits for a node whose heartbeat is due; 0 never waits), step_size (0.01 s),
pub_clock_frequency (100 Hz of simulated time), paused (false), gui (false), odometry_slip_stddev
(0.02, relative, for encoder odometry), cmd_vel_timeout (0.5 s), seed (0), gazebo_namespace
("gazebo": where services and the contacts topic live), robot_tf_in_namespace (false: a namespaced
robot's transforms on <namespace>/tf instead of /tf).

Publishes /clock; per robot (in its namespace): the drive's odometry topic and odom -> base tf,
each laser's LaserScan, base_pose_ground_truth (nav_msgs/Odometry in the world frame). Services
<ns>/spawn_urdf_model, spawn_sdf_model (people: SDF <actor>s), delete_model, get_model_state,
set_model_state (robots and people), pause_physics,
unpause_physics, reset_simulation, reset_world; topic <ns>/contacts (mbot_slam_navigation/Contact).
~real_time_factor (std_msgs/Float64, every 0.25 s wall: the factor reached) with a line every 10 s
wall when auto. Message stamps are simulated time; the node itself paces on the wall clock.

No publish waits for a subscriber (sim/nonblocking_publisher.py): a stopped or slow subscriber loses
messages, and the simulation keeps its rate.
"""
import math
import os
import threading
import time

import rospy
from geometry_msgs.msg import Pose2D, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from std_msgs.msg import Float64, Header
from std_srvs.srv import Empty, EmptyResponse
from tf2_msgs.msg import TFMessage

from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.nav.params import ParamReader
from mbot_slam_navigation.ros_msgs import pose_msg
from mbot_slam_navigation.sim.nonblocking_publisher import nonblocking_publisher
from mbot_slam_navigation.sim import pacing
from mbot_slam_navigation.sim.pacing import PacingError, make_pacer
from mbot_slam_navigation.sim.map_world import UNKNOWN_CHOICES
from mbot_slam_navigation.sim.sdf_world import World, load_world, parse_actors
from mbot_slam_navigation.sim.simulation import Simulation, SimulationError
from mbot_slam_navigation.transforms import (matrix_to_quaternion, quaternion_multiply, quaternion_to_yaw,
                                                 yaw_to_quaternion)
from mbot_slam_navigation.sim.urdf_robot import parse_urdf
from mbot_slam_navigation.sim.xmlutil import XmlError
from mbot_slam_navigation.srv import (DeleteModel, DeleteModelResponse, GetModelState, GetModelStateResponse,
                                      SetModelState, SetModelStateResponse, SpawnModel, SpawnModelResponse)


def _prefixed(namespace: str, frame: str) -> str:
    """gazebo_ros's tf_prefix rule: frames of a namespaced robot are '<ns>/<frame>'."""
    ns = namespace.strip('/')
    return '%s/%s' % (ns, frame) if ns else frame


class RobotIO:
    """A spawned robot's publishers and subscriber."""

    def __init__(self, node: 'SimNode', robot):
        self.robot = robot
        ns = robot.namespace.strip('/')
        prefix = '/' + ns + '/' if ns else ''
        drive = robot.spec.drive

        def topic(name):
            return name if name.startswith('/') else prefix + name

        self.odom_frame = _prefixed(ns, drive.odometry_frame)
        self.base_frame = _prefixed(ns, drive.robot_base_frame)
        self.odom_pub = nonblocking_publisher(topic(drive.odometry_topic), Odometry)
        self.truth_pub = nonblocking_publisher(topic('base_pose_ground_truth'), Odometry)
        self.scan_pubs = [nonblocking_publisher(topic(l.spec.topic), LaserScan) for l in robot.lasers]
        self.cmd_topic = topic(drive.command_topic)
        self.cmd_sub = rospy.Subscriber(self.cmd_topic, Twist, node.on_cmd_vel, callback_args=robot.name, queue_size=5)
        # the robot's own tf topic (robot_tf_in_namespace), else the node's /tf
        self.own_tf_pub = nonblocking_publisher(prefix + 'tf', TFMessage) if node.robot_tf_in_namespace and ns else None
        self.tf_pub = self.own_tf_pub or node.tf_pub

    def close(self):
        self.cmd_sub.unregister()
        for p in [self.odom_pub, self.truth_pub] + self.scan_pubs + ([self.own_tf_pub] if self.own_tf_pub else []):
            p.unregister()


def read_parameters(r: ParamReader) -> dict:
    """gazebo_ros's parameters that apply here, then ours; checked (ParamError)."""
    c = {'real_time_factor': r.raw('real_time_factor', 1.0,
                                   "simulated seconds per wall second: a number (0: as fast as possible) or 'auto' "
                                   '(as fast as the nodes keep up)', 'double or auto')}
    c['min_real_time_factor'] = r.number('min_real_time_factor', pacing.MIN_RTF, "'auto': the slowest pace",
                                         positive=True)
    c['max_real_time_factor'] = r.number('max_real_time_factor', pacing.MAX_RTF, "'auto': the fastest pace",
                                         positive=True)
    c['max_lag'] = r.number('max_lag', pacing.MAX_LAG,
                            '[s] simulated time the slowest node (its heartbeat) may fall behind before the clock waits',
                            positive=True)
    c['max_hold'] = r.number('max_hold', pacing.MAX_HOLD, '[s] wall time the clock waits for a late node at most',
                             minimum=0.0)
    c['step_size'] = r.number('step_size', 0.01, '[s] the physics step', positive=True)
    c['pub_clock_frequency'] = r.number('pub_clock_frequency', 100.0, '[Hz] simulated rate of /clock', positive=True)
    c['paused'] = r.boolean('paused', False, 'start paused (/gazebo/unpause_physics starts it)')
    c['gui'] = r.boolean('gui', False, 'open the top-down viewer window')
    c['gazebo_namespace'] = r.string('gazebo_namespace', 'gazebo', "the services' and topics' namespace")
    c['world_name'] = r.string('world_name', '', "the world: an SDF world file, or a map_server YAML map ('': an empty "
                               "world)")
    c['map_unknown'] = r.string('map_unknown', 'solid', "ours: with a map YAML as the world, its unknown cells are "
                                "'solid' (walls: a saved map's outside) or 'free'")
    if c['map_unknown'] not in UNKNOWN_CHOICES:
        raise ValueError("parameter %s must be 'solid' or 'free', got %r" % (r.where('map_unknown'), c['map_unknown']))
    c['odometry_slip_stddev'] = r.number('odometry_slip_stddev', 0.02,
                                         "ours: relative standard deviation of the wheels' slip (0: exact odometry)",
                                         minimum=0.0)
    c['cmd_vel_timeout'] = r.number('cmd_vel_timeout', 0.5, '[s] ours: the robot stops when cmd_vel falls silent this '
                                    'long (0: never)', minimum=0.0)
    c['seed'] = r.integer('seed', 0, "ours: the random generator's seed (slip, laser noise)")
    c['robot_tf_in_namespace'] = r.boolean(
        'robot_tf_in_namespace', False,
        "ours: a namespaced robot's odom -> base and wheel transforms go on <namespace>/tf instead of /tf, for robot "
        "stacks that remap /tf into their namespace (launch/robot.launch), so that a robot on a host of its own is not "
        "sent every robot's transforms; relay them to /tf for rviz (launch/base_station.launch)")
    return c


class SimNode:
    def __init__(self):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        c = read_parameters(r)
        r.report_unknown()
        self.pacer = make_pacer(c['real_time_factor'], min_rtf=c['min_real_time_factor'],
                                max_rtf=c['max_real_time_factor'], max_lag=c['max_lag'], max_hold=c['max_hold'])
        step = c['step_size']
        clock_hz = c['pub_clock_frequency']
        self.paused = c['paused']
        self.gui = c['gui']
        self.gz_ns = '/' + c['gazebo_namespace'].strip('/')
        self.robot_tf_in_namespace = c['robot_tf_in_namespace']
        world_path = c['world_name']
        if world_path:
            world = load_world(world_path, c['map_unknown'])  # raises XmlError or MapFileError naming the file
        else:
            world = World(name='empty')
        for w in world.warnings:
            rospy.logwarn('gazebo_sim: %s', w)
        rospy.loginfo('gazebo_sim: world "%s" from %s: %d shapes%s', world.name, world_path or '(empty)',
                      len(world.shapes), ', %d people' % len(world.actors) if world.actors else '')
        self.sim = Simulation(world, step_size=step,
                              slip_stddev=c['odometry_slip_stddev'], cmd_timeout=c['cmd_vel_timeout'],
                              seed=c['seed'])
        self.clock_period = 1.0 / clock_hz
        self.next_clock = 0.0
        self.lock = threading.RLock()
        self.io = {}
        self.clock_pub = nonblocking_publisher('/clock', Clock)
        self.contact_pub = rospy.Publisher(self.gz_ns + '/contacts', Contact, queue_size=20)
        self.tf_pub = nonblocking_publisher('/tf', TFMessage)
        self.rtf_pub = rospy.Publisher('~real_time_factor', Float64, queue_size=1)
        self.pacer_lock = threading.Lock()
        rospy.Subscriber('/sim_heartbeat', Header, self.on_heartbeat, queue_size=50)
        s = self.gz_ns + '/'
        rospy.Service(s + 'spawn_urdf_model', SpawnModel, self.on_spawn)
        rospy.Service(s + 'spawn_sdf_model', SpawnModel, self.on_spawn_sdf)
        rospy.Service(s + 'delete_model', DeleteModel, self.on_delete)
        rospy.Service(s + 'get_model_state', GetModelState, self.on_get_state)
        rospy.Service(s + 'set_model_state', SetModelState, self.on_set_state)
        rospy.Service(s + 'pause_physics', Empty, lambda _: self._set_paused(True))
        rospy.Service(s + 'unpause_physics', Empty, lambda _: self._set_paused(False))
        rospy.Service(s + 'reset_simulation', Empty, self.on_reset)
        rospy.Service(s + 'reset_world', Empty, self.on_reset)
        self.viewer = None
        if self.gui and not os.environ.get('DISPLAY'):
            rospy.logwarn('gazebo_sim: gui:=true but there is no display (DISPLAY is unset): running headless; '
                          'pass gui:=false to silence this')
        elif self.gui:
            from mbot_slam_navigation.sim.viewer import TopDownViewer
            self.viewer = TopDownViewer(world)

    # --- services and subscribers ---------------------------------------------------------------
    def _set_paused(self, paused):
        self.paused = paused
        rospy.loginfo('gazebo_sim: physics %s', 'paused' if paused else 'running')
        return EmptyResponse()

    def on_spawn(self, req):
        try:
            spec = parse_urdf(req.model_xml, 'model_xml of "%s"' % req.model_name)
            if req.reference_frame not in ('', 'world', 'map'):
                raise SimulationError('reference_frame "%s": only the world frame is supported' % req.reference_frame)
            q = req.initial_pose.orientation
            yaw = quaternion_to_yaw(q.x, q.y, q.z, q.w) if (q.x, q.y, q.z, q.w) != (0, 0, 0, 0) else 0.0
            with self.lock:
                robot = self.sim.spawn(req.model_name, spec, (req.initial_pose.position.x, req.initial_pose.position.y,
                                                              yaw), req.robot_namespace)
                self.io[robot.name] = RobotIO(self, robot)
        except (XmlError, SimulationError, ValueError) as e:
            rospy.logerr('gazebo_sim: cannot spawn "%s": %s', req.model_name, e)
            return SpawnModelResponse(False, 'SpawnModel: %s' % e)
        for w in spec.warnings:
            rospy.logwarn('gazebo_sim: %s', w)
        io = self.io[robot.name]
        rospy.loginfo('gazebo_sim: spawned "%s" (%s drive) at (%.2f, %.2f, %.2f rad), cmd on %s, lasers on %s',
                      robot.name, spec.drive.kind, robot.pose[0], robot.pose[1], robot.pose[2], io.cmd_topic,
                      ', '.join(p.resolved_name for p in io.scan_pubs) or 'none')
        return SpawnModelResponse(True, 'SpawnModel: model "%s" spawned' % robot.name)

    def on_spawn_sdf(self, req):
        """People at run time: SDF with one or more <actor>s. One actor takes the request's model_name;
        the initial pose moves the actor's pose and waypoints (Gazebo's spawn pose of a model)."""
        try:
            if req.reference_frame not in ('', 'world', 'map'):
                raise SimulationError('reference_frame "%s": only the world frame is supported' % req.reference_frame)
            actors = parse_actors(req.model_xml, 'model_xml of "%s"' % req.model_name)
            q = req.initial_pose.orientation
            yaw = quaternion_to_yaw(q.x, q.y, q.z, q.w) if (q.x, q.y, q.z, q.w) != (0, 0, 0, 0) else 0.0
            actors = [a.moved(req.initial_pose.position.x, req.initial_pose.position.y, yaw) for a in actors]
            if len(actors) == 1 and req.model_name:
                actors[0].name = req.model_name
            with self.lock:
                for a in actors:
                    self.sim.add_person(a)  # its script (and delay_start) counts from now
        except (XmlError, SimulationError, ValueError) as e:
            rospy.logerr('gazebo_sim: cannot spawn "%s": %s', req.model_name, e)
            return SpawnModelResponse(False, 'SpawnModel: %s' % e)
        for a in actors:
            rospy.loginfo('gazebo_sim: person "%s" (r %.2f m) %s', a.name, a.radius,
                          'walking %d waypoints' % len(a.waypoints) if a.waypoints
                          else 'standing at (%.2f, %.2f)' % (a.x, a.y))
        return SpawnModelResponse(True, 'SpawnModel: %s spawned' % ', '.join('"%s"' % a.name for a in actors))

    def on_delete(self, req):
        try:
            with self.lock:
                self.sim.delete(req.model_name)
                if req.model_name in self.io:
                    self.io.pop(req.model_name).close()
        except SimulationError as e:
            return DeleteModelResponse(False, 'DeleteModel: %s' % e)
        return DeleteModelResponse(True, 'DeleteModel: "%s" deleted' % req.model_name)

    def on_get_state(self, req):
        res = GetModelStateResponse()
        res.header.stamp = rospy.Time.from_sec(self.sim.time)
        res.header.frame_id = req.relative_entity_name or 'world'
        try:
            with self.lock:
                pose = world_pose = self.sim.model_pose(req.model_name)
                if req.relative_entity_name not in ('', 'world', 'map'):
                    ref = self.sim.model_pose(req.relative_entity_name)
                    c, s = math.cos(ref[2]), math.sin(ref[2])
                    dx, dy = pose[0] - ref[0], pose[1] - ref[1]
                    pose = (c * dx + s * dy, -s * dx + c * dy, pose[2] - ref[2])
                robot = self.sim.robots.get(req.model_name)
                v, w = (robot.drive.linear_velocity, robot.drive.angular_velocity) if robot else (0.0, 0.0)
        except SimulationError as e:
            res.success, res.status_message = False, 'GetModelState: %s' % e
            return res
        res.pose = pose_msg(*pose)
        res.twist.linear.x, res.twist.linear.y = v * math.cos(world_pose[2]), v * math.sin(world_pose[2])
        res.twist.angular.z = w
        res.success, res.status_message = True, 'GetModelState: got properties'
        return res

    def on_set_state(self, req):
        st = req.model_state
        try:
            if st.reference_frame not in ('', 'world', 'map'):
                raise SimulationError('reference_frame "%s": only the world frame is supported' % st.reference_frame)
            q = st.pose.orientation
            with self.lock:
                self.sim.set_pose(st.model_name, (st.pose.position.x, st.pose.position.y,
                                                  quaternion_to_yaw(q.x, q.y, q.z, q.w)))
        except SimulationError as e:
            return SetModelStateResponse(False, 'SetModelState: %s' % e)
        return SetModelStateResponse(True, 'SetModelState: set model state done')

    def on_reset(self, _req):
        with self.lock:
            self.sim.reset()
            self.next_clock = 0.0
        rospy.loginfo('gazebo_sim: simulation reset')
        return EmptyResponse()

    def on_heartbeat(self, msg):
        """A consumer of simulated time says how far it has got (sim/pacing.py)."""
        stamp = msg.stamp.to_sec()
        lag = self.sim.time - stamp
        with self.pacer_lock:
            self.pacer.heartbeat(msg.frame_id or '(unnamed)', lag, time.monotonic(), stamp)

    def pace(self, now: float, wall0: float, sim0: float):
        """Sleeps as the real-time factor requires; returns the (wall, sim) pair to pace from."""
        wall = time.monotonic()
        with self.pacer_lock:
            decided = self.pacer.update(wall, now)
            p = self.pacer
            if decided:
                self.rtf_pub.publish(Float64(p.achieved))
                if p.went_auto:
                    p.went_auto = False
                    rospy.logwarn('gazebo_sim: real_time_factor 0 runs /clock %.1f s ahead of %s; running as fast as '
                                  'the nodes keep up instead, as real_time_factor:=auto does (auto also bounds it with '
                                  '~min_real_time_factor/~max_real_time_factor)' % (p.worst[1], p.worst[0]))
                if p.auto and wall - self.last_report >= 10.0:
                    self.last_report = wall
                    rospy.loginfo('gazebo_sim: running at %.1fx real time (auto%s; waited %.1f s for late nodes, %d '
                                  'times, passed one by after %.2f s %d times)' % (
                                      p.achieved, '; slowest: %s %.2f s behind' % p.worst if p.worst[0]
                                      else '; no node reports lag', p.held_s, p.holds, p.max_hold, p.passed_by))
            rtf = p.rtf
        if decided:
            return wall, now  # pace the new factor from here
        if math.isinf(rtf):
            return wall0, sim0
        ahead = (now - sim0) / rtf - (wall - wall0)
        if ahead > 0:
            time.sleep(ahead)
        elif ahead < -0.1:
            return wall, now  # starved of CPU: go on at the factor, do not race to catch up
        return wall0, sim0

    def on_cmd_vel(self, msg, name):
        with self.lock:
            if name not in self.sim.robots:
                return
            if not self.sim.command(name, msg.linear.x, msg.angular.z):
                rospy.logwarn_throttle(2.0, 'gazebo_sim: ignoring a non-finite command on %s (linear.x=%r, '
                                       'angular.z=%r); "%s" keeps its previous command',
                                       self.io[name].cmd_topic, msg.linear.x, msg.angular.z, name)

    # --- the loop ---------------------------------------------------------------------------------
    def publish_robot(self, io: RobotIO, stamp, due_odom: bool, due_lasers):
        robot, sim = io.robot, self.sim
        if due_odom:
            ox, oy, oyaw = (float(v) for v in robot.drive.odom_pose)
            v, w = robot.drive.linear_velocity, robot.drive.angular_velocity
            odom = Odometry()
            odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, io.odom_frame, io.base_frame
            odom.pose.pose = pose_msg(ox, oy, oyaw)
            cx, cy, cyaw = robot.spec.drive.covariance
            odom.pose.covariance[0], odom.pose.covariance[7], odom.pose.covariance[35] = cx, cy, cyaw
            odom.twist.twist.linear.x, odom.twist.twist.angular.z = v, w
            io.odom_pub.publish(odom)
            if io.truth_pub.get_num_connections() > 0:  # building it costs; evaluation tools subscribe
                truth = Odometry()
                truth.header.stamp, truth.header.frame_id, truth.child_frame_id = stamp, 'world', io.base_frame
                truth.pose.pose = pose_msg(*robot.pose)
                truth.twist.twist.linear.x, truth.twist.twist.angular.z = v, w
                io.truth_pub.publish(truth)
            transforms = []
            if robot.spec.drive.publish_odom_tf:
                t = TransformStamped()
                t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, io.odom_frame, io.base_frame
                t.transform.translation.x, t.transform.translation.y = ox, oy
                (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                 t.transform.rotation.w) = yaw_to_quaternion(oyaw)
                transforms = [t]
            if robot.spec.drive.publish_wheel_tf:
                transforms += self.wheel_transforms(robot, stamp)
            if transforms:
                io.tf_pub.publish(TFMessage(transforms))
        for k in due_lasers:
            laser = robot.lasers[k]
            s = laser.spec
            scan = LaserScan()
            scan.header.stamp = stamp
            scan.header.frame_id = _prefixed(robot.namespace, s.frame_id)
            scan.angle_min, scan.angle_max, scan.angle_increment = s.angle_min, s.angle_max, s.angle_increment
            scan.scan_time = 1.0 / s.update_rate
            scan.range_min, scan.range_max = s.range_min, s.range_max
            scan.ranges = sim.scan(robot, laser).tolist()
            io.scan_pubs[k].publish(scan)

    @staticmethod
    def wheel_transforms(robot, stamp):
        """publishWheelTF: each wheel link turned by its accumulated angle about its joint axis."""
        out = []
        angles = robot.drive.wheel_angles
        for wheel in robot.spec.wheels:
            half = 0.5 * float(angles[wheel.side])
            spin = tuple(wheel.axis * math.sin(half)) + (math.cos(half),)
            t = TransformStamped()
            t.header.stamp = stamp
            t.header.frame_id = _prefixed(robot.namespace, wheel.parent)
            t.child_frame_id = _prefixed(robot.namespace, wheel.child)
            t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = wheel.origin[:3, 3]
            (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
             t.transform.rotation.w) = quaternion_multiply(matrix_to_quaternion(wheel.origin), spin)
            out.append(t)
        return out

    def run(self):
        wall0, sim0 = time.monotonic(), self.sim.time
        last_viewer = 0.0
        self.last_report = wall0
        while not rospy.is_shutdown():
            if self.paused:
                time.sleep(0.01)
                wall0, sim0 = time.monotonic(), self.sim.time
                with self.pacer_lock:
                    self.pacer.restart(wall0, sim0)
                continue
            with self.pacer_lock:
                late = self.pacer.late(self.sim.time + self.sim.step_size, time.monotonic())
            if late is not None:
                time.sleep(0.001)  # its heartbeat is due: a few wall ms at most (pacing.py)
                continue
            with self.lock:
                contacts = self.sim.step()
                now = self.sim.time
                stamp = rospy.Time.from_sec(now)
                publish_clock = now + 1e-9 >= self.next_clock
                if publish_clock:
                    self.next_clock = now + self.clock_period
                work = []
                for io in self.io.values():
                    r = io.robot
                    due_odom = now + 1e-9 >= r.next_odom_time
                    if due_odom:
                        r.next_odom_time = now + 1.0 / r.spec.drive.update_rate
                    due_lasers = []
                    for k, laser in enumerate(r.lasers):
                        if now + 1e-9 >= laser.next_time:
                            laser.next_time = now + 1.0 / laser.spec.update_rate
                            due_lasers.append(k)
                    if due_odom or due_lasers:
                        work.append((io, due_odom, due_lasers))
                for io, due_odom, due_lasers in work:
                    self.publish_robot(io, stamp, due_odom, due_lasers)
            if publish_clock:
                self.clock_pub.publish(Clock(clock=stamp))
            for e in contacts:
                r = e.robot
                if e.robot_at_fault:
                    rospy.logwarn('gazebo_sim: "%s" collided with %s at (%.2f, %.2f); %d collisions so far',
                                  r.name, 'the world' if e.kind == 'world' else '%s "%s"' % (e.kind, e.other),
                                  r.pose[0], r.pose[1], r.collisions)
                else:
                    rospy.loginfo('gazebo_sim: person "%s" walked into "%s" at (%.2f, %.2f) (not the robot\'s fault)',
                                  e.other, r.name, r.pose[0], r.pose[1])
                c = Contact(model_name=r.name, pose=Pose2D(*r.pose), total_collisions=r.collisions, other=e.other,
                            other_kind=e.kind, robot_at_fault=e.robot_at_fault)
                c.header.stamp, c.header.frame_id = stamp, 'world'
                self.contact_pub.publish(c)
            if self.viewer is not None and time.monotonic() - last_viewer > 0.05:
                last_viewer = time.monotonic()
                with self.lock:
                    self.viewer.draw(self.sim)
            if now < sim0:  # reset_simulation took time back: pace from here
                wall0, sim0 = time.monotonic(), now
                with self.pacer_lock:
                    self.pacer.restart(wall0, now)
            wall0, sim0 = self.pace(now, wall0, sim0)


def main():
    rospy.init_node('gazebo_sim')
    try:
        node = SimNode()
    except (XmlError, ValueError, PacingError) as e:
        rospy.logfatal('gazebo_sim: %s', e)
        raise SystemExit(1)
    node.run()
