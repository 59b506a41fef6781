"""amcl: ROS amcl's node over the C++ particle filter (include/mbot_slam_navigation/core/amcl.h).

Interface as ROS's amcl: subscribes `scan`, `initialpose` (rviz's 2D Pose Estimate), `map` (with
use_map_topic, otherwise the map comes once from the `static_map` service); publishes `amcl_pose`
(latched), `particlecloud` (latched) and map -> odom on tf (future-dated by transform_tolerance,
unless tf_broadcast is false); serves `global_localization`, `request_nomotion_update` and
`set_map`. Parameters: ROS amcl's names and defaults (read_parameters()), plus ~seed (0) for the
random generator and ~recovery_search_radius (3 m) / ~recovery_search_updates (20): where and how
long to search when the scans stop fitting the map (Localizer).

Differences from ROS, on purpose: "diff" and "omni" are the corrected odometry models (ROS's
"-corrected" ones: sqrt(alpha * motion^2) is the standard deviation); yaw bins wrap when clusters are
formed; resampling is low-variance and linear in the particle count; a second publisher of map ->
odom while tf_broadcast is true is reported as an error (the robot would jump between the two).
"""
import math
import threading
from typing import Optional, Tuple

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseArray, PoseWithCovarianceStamped, TransformStamped
from nav_msgs.msg import OccupancyGrid
from nav_msgs.srv import GetMap, SetMap, SetMapResponse
from sensor_msgs.msg import LaserScan
from std_srvs.srv import Empty, EmptyResponse
from tf2_msgs.msg import TFMessage

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.nav.localizer import Localizer
from mbot_slam_navigation.ros_msgs import pose_msg
from mbot_slam_navigation.transforms import normalize_angle, quaternion_to_yaw, yaw_to_quaternion

ODOM_MODELS = {'diff': 'diff', 'diff-corrected': 'diff', 'omni': 'omni', 'omni-corrected': 'omni'}
LASER_MODELS = {'likelihood_field': 'likelihood_field', 'likelihood_field_prob': 'likelihood_field', 'beam': 'beam'}
# ROS amcl parameters this node accepts but does not implement (beam skipping, selective resampling).
IGNORED = ('do_beamskip', 'beam_skip_distance', 'beam_skip_threshold', 'beam_skip_error_threshold',
           'selective_resampling', 'restore_defaults')
THROTTLE = 10.0  # [s] between repeats of one warning


def read_parameters(r: ParamReader):
    """ROS amcl's parameters and defaults, checked; returns (core params, node settings dict)."""
    p = _core._AmclParams()  # its defaults are ROS amcl's (core/amcl.h)
    p.min_particles = r.integer('min_particles', p.min_particles, 'fewest particles', minimum=1)
    p.max_particles = r.integer('max_particles', p.max_particles, 'most particles', minimum=1)
    if p.max_particles < p.min_particles:
        raise ParamError('parameter %s (%d) must be >= %s (%d)' % (r.where('max_particles'), p.max_particles,
                                                                 r.where('min_particles'), p.min_particles))
    p.kld_err = r.number('kld_err', p.kld_err, 'largest error between the true and the estimated distribution (KLD)',
                         positive=True)
    p.kld_z = r.number('kld_z', p.kld_z, 'upper standard normal quantile for (1 - p) of that error bound',
                       positive=True)
    p.recovery_alpha_slow = r.number('recovery_alpha_slow', p.recovery_alpha_slow,
                                     'decay rate of the slow average weight (0: no random particles)', minimum=0.0)
    p.recovery_alpha_fast = r.number('recovery_alpha_fast', p.recovery_alpha_fast,
                                     'decay rate of the fast average weight (0: no random particles)', minimum=0.0)
    odom_model = r.string('odom_model_type', 'diff', 'diff, omni, diff-corrected or omni-corrected (all corrected here)')
    if odom_model not in ODOM_MODELS:
        raise ParamError('parameter %s must be one of %s, got %r' % (r.where('odom_model_type'),
                                                                     ', '.join(ODOM_MODELS), odom_model))
    p.odom_model = ODOM_MODELS[odom_model]
    for i, what in enumerate(('rotation noise from rotation', 'rotation noise from translation',
                              'translation noise from translation', 'translation noise from rotation',
                              'omni: strafe noise from translation'), start=1):
        key = 'alpha%d' % i
        setattr(p, key, r.number('odom_' + key, getattr(p, key), 'odometry model: ' + what, minimum=0.0))
    laser_model = r.string('laser_model_type', 'likelihood_field',
                           'likelihood_field, likelihood_field_prob (run as likelihood_field) or beam')
    if laser_model not in LASER_MODELS:
        raise ParamError('parameter %s must be one of %s, got %r' % (r.where('laser_model_type'),
                                                                     ', '.join(LASER_MODELS), laser_model))
    if laser_model == 'likelihood_field_prob':
        r.warn('parameter %s: likelihood_field_prob is run as likelihood_field (no beam skipping)'
               % r.where('laser_model_type'))
    p.laser_model = LASER_MODELS[laser_model]
    p.max_beams = r.integer('laser_max_beams', p.max_beams, 'beams of each scan used in the update', minimum=2)
    p.z_hit = r.number('laser_z_hit', p.z_hit, 'mixture weight of the hit part of the laser model', minimum=0.0)
    p.z_short = r.number('laser_z_short', p.z_short, 'beam model: mixture weight of the short part', minimum=0.0)
    p.z_max = r.number('laser_z_max', p.z_max, 'beam model: mixture weight of the max-range part', minimum=0.0)
    p.z_rand = r.number('laser_z_rand', p.z_rand, 'mixture weight of the random part', minimum=0.0)
    p.sigma_hit = r.number('laser_sigma_hit', p.sigma_hit, '[m] standard deviation of the hit part', positive=True)
    p.lambda_short = r.number('laser_lambda_short', p.lambda_short, 'beam model: exponential decay of the short part',
                              positive=True)
    p.likelihood_max_dist = r.number('laser_likelihood_max_dist', p.likelihood_max_dist,
                                     '[m] likelihood field: farthest obstacle distance computed', positive=True)
    try:
        p.validate()
    except ValueError as e:
        raise ParamError('%s: %s' % (r.ns, e)) from None
    s = {
        'update_min_d': r.number('update_min_d', 0.2, '[m] travel before a filter update', minimum=0.0),
        'update_min_a': r.number('update_min_a', math.pi / 6.0, '[rad] turn before a filter update', minimum=0.0),
        'resample_interval': r.integer('resample_interval', 2, 'filter updates between resamplings', minimum=1),
        'transform_tolerance': r.number('transform_tolerance', 0.1, '[s] how far ahead map -> odom is stamped',
                                        minimum=0.0),
        'gui_publish_rate': r.number('gui_publish_rate', -1.0, '[Hz] most often particlecloud is published (-1: no limit)'),
        'save_pose_rate': r.number('save_pose_rate', 0.5,
                                   '[Hz] how often the estimate is stored in ~initial_pose_* and ~initial_cov_* '
                                   '(-1: never)'),
        'use_map_topic': r.boolean('use_map_topic', False, 'read the map topic instead of calling static_map'),
        'first_map_only': r.boolean('first_map_only', False, 'keep the first map, ignore later ones'),
        'laser_min_range': r.number('laser_min_range', -1.0, "[m] shortest range used (-1: the scan's range_min)"),
        'laser_max_range': r.number('laser_max_range', -1.0, "[m] longest range used (-1: the scan's range_max)"),
        'odom_frame_id': r.frame('odom_frame_id', 'odom', 'the odometry frame'),
        'base_frame_id': r.frame('base_frame_id', 'base_link', "the robot's base frame"),
        'global_frame_id': r.frame('global_frame_id', 'map', 'the map frame'),
        'tf_broadcast': r.boolean('tf_broadcast', True, 'broadcast map -> odom'),
        'initial_pose': (r.number('initial_pose_x', 0.0, '[m] initial pose mean, x'),
                         r.number('initial_pose_y', 0.0, '[m] initial pose mean, y'),
                         r.number('initial_pose_a', 0.0, '[rad] initial pose mean, yaw')),
        'initial_cov': (r.number('initial_cov_xx', 0.5 * 0.5, '[m^2] initial pose covariance, x x', minimum=0.0),
                        r.number('initial_cov_yy', 0.5 * 0.5, '[m^2] initial pose covariance, y y', minimum=0.0),
                        r.number('initial_cov_aa', (math.pi / 12) ** 2, '[rad^2] initial pose covariance, yaw yaw',
                                 minimum=0.0)),
        'seed': r.integer('seed', 0, "ours: the random generator's seed", minimum=0),
        'recovery_search_radius': r.number('recovery_search_radius', 3.0,
                                           '[m] ours: how far around the estimate to search when the scans stop '
                                           'fitting the map (0: leave it to recovery_alpha_*)', minimum=0.0),
        'recovery_search_updates': r.integer('recovery_search_updates', 20,
                                             'ours: how many updates that search lasts', minimum=1),
    }
    for key in IGNORED:
        if r.has(key):
            r.warn('parameter %s is not implemented here and is ignored' % r.where(key))
        r.ignored(key, "ROS amcl's beam skipping and selective resampling are not implemented")
    return p, s


class AmclNode:
    def __init__(self):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        try:
            self.params, self.s = read_parameters(r)
        except ParamError as e:
            rospy.logfatal('amcl: %s', e)
            raise SystemExit(1)
        r.report_unknown()
        self.lock = threading.RLock()
        self.pf = _core._Amcl(self.params, self.s['seed'])
        self.loc = Localizer(self.pf, self.s['update_min_d'], self.s['update_min_a'], self.s['resample_interval'],
                             self.s['recovery_search_radius'], self.s['recovery_search_updates'])
        self.map_received = False
        self.laser_cache = {}   # frame_id -> (x [m], y [m], 3x3 rotation) of the laser in the base frame
        self.map_to_odom: Optional[Tuple[float, float, float]] = None
        self.last_estimate: Optional[Tuple[float, float, float]] = None
        self.last_cov = self.s['initial_cov']  # (xx [m^2], yy [m^2], aa [rad^2]) of the last estimate
        self.last_cloud_time = rospy.Time(0)

        self.tf = tf2_ros.Buffer(rospy.Duration(30.0))
        self.tf_listener = tf2_ros.TransformListener(self.tf)
        self.tf_pub = tf2_ros.TransformBroadcaster()
        self.pose_pub = rospy.Publisher('amcl_pose', PoseWithCovarianceStamped, queue_size=2, latch=True)
        self.cloud_pub = rospy.Publisher('particlecloud', PoseArray, queue_size=2, latch=True)
        rospy.Service('global_localization', Empty, self.global_localization)
        rospy.Service('request_nomotion_update', Empty, self.nomotion_update)
        rospy.Service('set_map', SetMap, self.set_map)
        rospy.Subscriber('/tf', TFMessage, self.watch_tf, queue_size=50)
        rospy.Subscriber('initialpose', PoseWithCovarianceStamped, self.initial_pose, queue_size=2)
        if self.s['use_map_topic']:
            self.map_sub = rospy.Subscriber('map', OccupancyGrid, self.map_received_cb, queue_size=1)
            rospy.loginfo('amcl: waiting for a map on %s', self.map_sub.resolved_name)
        else:
            self.request_map()
        rospy.Subscriber('scan', LaserScan, self.scan_received, queue_size=1, buff_size=2 ** 22)
        if self.s['save_pose_rate'] > 0:
            rospy.Timer(rospy.Duration(1.0 / self.s['save_pose_rate']), self.save_pose)

    # ---------------------------------------------------------------------------------------- map
    def request_map(self):
        rospy.loginfo('amcl: requesting the map from the static_map service...')
        while not rospy.is_shutdown():
            try:
                rospy.wait_for_service('static_map', timeout=5.0)
                self.handle_map(rospy.ServiceProxy('static_map', GetMap)().map)
                return
            except (rospy.ROSException, rospy.ServiceException) as e:
                rospy.logwarn_throttle(THROTTLE, 'amcl: no map from static_map yet (%s); is map_server running? '
                                                 'Or set use_map_topic true to read the map topic' % e)

    def map_received_cb(self, msg: OccupancyGrid):
        if self.s['first_map_only'] and self.map_received:
            return
        self.handle_map(msg)

    def handle_map(self, msg: OccupancyGrid) -> bool:
        info = msg.info
        if info.width * info.height != len(msg.data) or info.resolution <= 0:
            rospy.logerr('amcl: map in frame "%s" is malformed (%d x %d cells, %d values, resolution %g); ignored',
                         msg.header.frame_id, info.width, info.height, len(msg.data), info.resolution)
            return False
        q = info.origin.orientation
        yaw = quaternion_to_yaw(q.x, q.y, q.z, q.w)
        if abs(yaw) > 1e-6:
            rospy.logwarn('amcl: the map origin is rotated by %.3f rad; amcl uses its position only, as ROS amcl', yaw)
        if msg.header.frame_id and msg.header.frame_id.lstrip('/') != self.s['global_frame_id']:
            rospy.logwarn('amcl: the map is in frame "%s" but global_frame_id is "%s"', msg.header.frame_id,
                          self.s['global_frame_id'])
        data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
        amap = _core._AmclMap(data, info.resolution, (info.origin.position.x, info.origin.position.y))
        if amap.free_cell_count() == 0:
            rospy.logerr('amcl: the map has no free cells; ignored')
            return False
        with self.lock:
            self.pf.set_map(amap)
            self.map_received = True
            # A new map (SLAM publishes one every few seconds): start again from the last estimate and
            # its spread, as ROS amcl does through the pose it saves; else from the initial pose.
            if self.last_estimate is not None:
                mean, cov = self.last_estimate, self.last_cov
            else:
                mean, cov = self.s['initial_pose'], self.s['initial_cov']
            self.pf.init_gaussian(np.array(mean), np.diag(cov))
            self.loc.reinitialized()
        rospy.loginfo('amcl: received a %d x %d map @ %.3f m/cell; %d particles around (%.2f, %.2f, %.2f)',
                      info.width, info.height, info.resolution, self.params.max_particles, *mean)
        return True

    # ----------------------------------------------------------------------------------- services
    def global_localization(self, _req):
        with self.lock:
            if not self.map_received:
                rospy.logwarn('amcl: global_localization before a map arrived; nothing done')
                return EmptyResponse()
            self.pf.init_uniform()
            self.loc.reinitialized()
        rospy.loginfo('amcl: global localization: %d particles spread over the free space', self.params.max_particles)
        return EmptyResponse()

    def nomotion_update(self, _req):
        with self.lock:
            self.loc.force_update = True
        rospy.loginfo('amcl: the next scan will update the filter without motion')
        return EmptyResponse()

    def set_map(self, req):
        ok = self.handle_map(req.map)
        if ok:
            self.set_pose(req.initial_pose)
        return SetMapResponse(success=ok)

    # -------------------------------------------------------------------------------- initial pose
    def initial_pose(self, msg: PoseWithCovarianceStamped):
        frame = msg.header.frame_id.lstrip('/')
        if not frame:
            rospy.logwarn('amcl: initial pose with an empty frame_id; taking it in %s', self.s['global_frame_id'])
        elif frame != self.s['global_frame_id']:
            rospy.logwarn('amcl: ignoring the initial pose in frame "%s"; initial poses must be in the global frame "%s"',
                          frame, self.s['global_frame_id'])
            return
        self.set_pose(msg)

    def set_pose(self, msg: PoseWithCovarianceStamped):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        values = (p.x, p.y, q.x, q.y, q.z, q.w)
        norm = math.sqrt(q.x ** 2 + q.y ** 2 + q.z ** 2 + q.w ** 2)
        if not all(math.isfinite(v) for v in values) or norm < 1e-6:
            rospy.logerr('amcl: ignoring an initial pose with NaN, infinite or zero-length values: %s', values)
            return
        yaw = quaternion_to_yaw(q.x / norm, q.y / norm, q.z / norm, q.w / norm)
        c = msg.pose.covariance
        cov = np.array([[c[0], c[1], 0.0], [c[6], c[7], 0.0], [0.0, 0.0, c[35]]])
        with self.lock:
            if not self.map_received:
                self.s['initial_pose'] = (p.x, p.y, yaw)
                self.s['initial_cov'] = (c[0], c[7], c[35])
                rospy.loginfo('amcl: initial pose (%.2f, %.2f, %.2f) kept until a map arrives', p.x, p.y, yaw)
                return
            self.pf.init_gaussian(np.array([p.x, p.y, yaw]), cov)
            self.loc.reinitialized()
        rospy.loginfo('amcl: initial pose set to (%.3f, %.3f, %.3f)', p.x, p.y, yaw)

    # ------------------------------------------------------------------------------- tf watchdog
    def watch_tf(self, msg: TFMessage):
        if not self.s['tf_broadcast']:
            return
        caller = msg._connection_header.get('callerid', '?') if hasattr(msg, '_connection_header') else '?'
        if caller == rospy.get_name():
            return
        for t in msg.transforms:
            if (t.header.frame_id.lstrip('/') == self.s['global_frame_id']
                    and t.child_frame_id.lstrip('/') == self.s['odom_frame_id']):
                rospy.logerr_throttle(
                    THROTTLE, 'amcl: %s also publishes %s -> %s (SLAM running?). Two publishers of one transform make '
                              'the robot jump between their estimates: set ~tf_broadcast false on amcl, or do not '
                              'start amcl while SLAM owns the transform' % (caller, self.s['global_frame_id'],
                                                                           self.s['odom_frame_id']))

    # -------------------------------------------------------------------------------------- scans
    def laser_geometry(self, scan: LaserScan):
        """The laser's position in the base frame and its beam angles there (handles lasers mounted
        rotated or upside down, as ROS amcl does by transforming two beam directions)."""
        frame = scan.header.frame_id
        cached = self.laser_cache.get(frame)
        if cached is None:
            try:
                t = self.tf.lookup_transform(self.s['base_frame_id'], frame, rospy.Time(0), rospy.Duration(0.5))
            except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
                rospy.logwarn_throttle(THROTTLE, 'amcl: no transform from the laser frame "%s" to %s (%s); scan '
                                                 'skipped' % (frame, self.s['base_frame_id'], e))
                return None
            q = t.transform.rotation
            x, y, z, w = q.x, q.y, q.z, q.w
            rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
            cached = (t.transform.translation.x, t.transform.translation.y, rot)
            self.laser_cache[frame] = cached
        x, y, rot = cached
        d0 = rot @ [math.cos(scan.angle_min), math.sin(scan.angle_min), 0.0]
        a1 = scan.angle_min + scan.angle_increment
        d1 = rot @ [math.cos(a1), math.sin(a1), 0.0]
        angle_min = math.atan2(d0[1], d0[0])
        increment = normalize_angle(math.atan2(d1[1], d1[0]) - angle_min)
        return (x, y), angle_min, increment

    def odom_pose(self, stamp) -> Optional[Tuple[float, float, float]]:
        try:
            t = self.tf.lookup_transform(self.s['odom_frame_id'], self.s['base_frame_id'], stamp, rospy.Duration(0.1))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(THROTTLE, 'amcl: cannot find %s in %s at the scan time (%s); scan skipped'
                                   % (self.s['base_frame_id'], self.s['odom_frame_id'], e))
            return None
        q = t.transform.rotation
        return t.transform.translation.x, t.transform.translation.y, quaternion_to_yaw(q.x, q.y, q.z, q.w)

    def scan_received(self, scan: LaserScan):
        if not self.map_received:
            return
        if not scan.ranges or not (scan.range_max > 0) or not math.isfinite(scan.angle_increment):
            rospy.logwarn_throttle(THROTTLE, 'amcl: malformed scan in frame "%s" (%d ranges, range_max %g); skipped'
                                   % (scan.header.frame_id, len(scan.ranges), scan.range_max))
            return
        geometry = self.laser_geometry(scan)
        pose = self.odom_pose(scan.header.stamp)
        if geometry is None or pose is None:
            return
        (lx, ly), angle_min, increment = geometry
        range_min = max(scan.range_min, self.s['laser_min_range']) if self.s['laser_min_range'] > 0 else scan.range_min
        range_max = min(scan.range_max, self.s['laser_max_range']) if self.s['laser_max_range'] > 0 else scan.range_max
        with self.lock:
            if self.loc.update(pose, angle_min, increment, range_min, range_max, scan.ranges, (lx, ly)):
                self.publish_estimate(scan.header.stamp)
                self.publish_cloud(scan.header.stamp)
                self.report_fit()
            self.send_transform(scan.header.stamp)

    def report_fit(self):
        """One line when the scans stop fitting the map around the estimate, and one when they fit again."""
        change = self.loc.fit_change
        if change is None and self.loc.search_change != 'global':
            return
        x, y, _ = self.last_estimate
        if change == 'lost':
            recovering = self.params.recovery_alpha_slow > 0 and self.params.recovery_alpha_fast > 0
            if self.loc.search_radius > 0:
                what = ('searching within %.1f m of it (recovery_search_radius), then, after %d updates, the whole map'
                        % (self.loc.search_radius, self.loc.search_updates))
            elif recovering:
                what = 'recovery_alpha_slow/fast are set, so random particles are being injected'
            else:
                what = ('recovery_alpha_slow/fast and recovery_search_radius are 0, so amcl will not find it by '
                        'itself: call the global_localization service or give a 2D Pose Estimate')
            rospy.logwarn('amcl: the scans fit the map at %.0f%% of before around the estimate (%.2f, %.2f): '
                          'the robot may have been carried elsewhere; %s', 100.0 * self.loc.fit.ratio(), x, y, what)
        elif self.loc.search_change == 'global':
            rospy.logwarn('amcl: not found within %.1f m after %d updates; spreading the particles over the whole '
                          'map, as global_localization does', self.loc.search_radius, self.loc.search_updates)
        else:
            rospy.loginfo('amcl: the scans fit the map again around (%.2f, %.2f)', x, y)

    # ------------------------------------------------------------------------------------ outputs
    def publish_estimate(self, stamp):
        (x, y, yaw), cov, _weight, _clusters = self.loc.estimate()
        msg = PoseWithCovarianceStamped()
        msg.header.frame_id = self.s['global_frame_id']
        msg.header.stamp = stamp
        msg.pose.pose = pose_msg(x, y, yaw)
        c = [0.0] * 36
        c[0], c[1], c[6], c[7], c[35] = cov[0, 0], cov[0, 1], cov[1, 0], cov[1, 1], cov[2, 2]
        msg.pose.covariance = c
        self.pose_pub.publish(msg)
        self.last_estimate = (x, y, yaw)
        self.last_cov = (cov[0, 0], cov[1, 1], cov[2, 2])
        self.map_to_odom = self.loc.map_to_odom(self.last_estimate)

    def publish_cloud(self, stamp):
        rate = self.s['gui_publish_rate']
        since = (stamp - self.last_cloud_time).to_sec()
        if rate > 0 and 0.0 <= since < 1.0 / rate:  # (negative: simulated time was reset)
            return
        self.last_cloud_time = stamp
        cloud = PoseArray()
        cloud.header.frame_id = self.s['global_frame_id']
        cloud.header.stamp = stamp
        cloud.poses = [pose_msg(px, py, pa) for px, py, pa, _w in self.pf.particles()]
        self.cloud_pub.publish(cloud)

    def send_transform(self, stamp):
        if self.map_to_odom is None or not self.s['tf_broadcast']:
            return
        t = TransformStamped()
        t.header.frame_id = self.s['global_frame_id']
        t.child_frame_id = self.s['odom_frame_id']
        t.header.stamp = stamp + rospy.Duration(self.s['transform_tolerance'])
        t.transform.translation.x, t.transform.translation.y = self.map_to_odom[:2]
        q = t.transform.rotation
        q.x, q.y, q.z, q.w = yaw_to_quaternion(self.map_to_odom[2])
        self.tf_pub.sendTransform(t)

    def save_pose(self, _event):
        """As ROS amcl: the last estimate goes to ~initial_pose_* so a restart resumes from it."""
        if self.last_estimate is None:
            return
        x, y, yaw = self.last_estimate
        rospy.set_param('~initial_pose_x', x)
        rospy.set_param('~initial_pose_y', y)
        rospy.set_param('~initial_pose_a', yaw)
        for key, value in zip(('initial_cov_xx', 'initial_cov_yy', 'initial_cov_aa'), self.last_cov):
            rospy.set_param('~' + key, float(value))


def main() -> None:
    rospy.init_node('amcl')
    AmclNode()
    rospy.spin()
