"""CARMEN reading and the relations metric on tiny fixtures."""
import math
import os
import time

import numpy as np
import pytest

from mbot_slam_navigation.slam.carmen import CarmenError, read_log
from mbot_slam_navigation.slam.offline import BagError, read_rosbag
from mbot_slam_navigation.slam.relations import evaluate, pose_at
from mbot_slam_navigation.transforms import compose2d, relative2d

DATA = os.path.join(os.path.dirname(__file__), '..', 'data')


def test_carmen_lines():
    scans = read_log(os.path.join(DATA, 'tiny.clf'))
    assert len(scans) == 3
    a, b, c = scans
    # 4 beams (even): 180 degrees from -90 in 45-degree steps; 81.91 kept ("no measurement", skipped by maxRange)
    assert a.angle_min == pytest.approx(-math.pi / 2) and a.angle_increment == pytest.approx(math.pi / 4)
    assert a.ranges[2] == pytest.approx(81.91) and a.laser_pose == pytest.approx((0.1, 0.0, 0.0))
    # 5 beams (odd): -90 to +90 inclusive; the laser pose is relative to the robot's odometry
    assert b.angle_increment == pytest.approx(math.pi / 4)
    assert b.odom == pytest.approx((1.0, 0.0, math.pi / 2)) and b.laser_pose == pytest.approx((0.0, -0.1, 0.0), abs=1e-6)
    assert c.time == pytest.approx(10.45) and len(c.ranges) == 5 and c.odom == pytest.approx((2.0, 0.5, 0.0))


def test_carmen_errors_name_the_line():
    with pytest.raises(CarmenError, match=r'short_flaser.clf:1: cannot read FLASER'):
        read_log(os.path.join(DATA, 'short_flaser.clf'))


def test_relations_metric():
    rng = np.random.default_rng(4)
    times = np.arange(0.0, 50.0, 0.5)
    poses = np.cumsum(rng.normal(0, 0.2, size=(len(times), 3)), axis=0)
    rel = []
    for k in range(0, len(times) - 3, 3):
        x, y, yaw = relative2d(poses[k], poses[k + 3])
        rel.append((times[k], times[k + 3], x, y, yaw))
    rel = np.array(rel)
    exact = evaluate(times, poses, rel)
    assert exact.trans_mean == pytest.approx(0.0, abs=1e-9) and exact.rot_mean == pytest.approx(0.0, abs=1e-9)
    # A constant offset of the whole trajectory changes no relative motion...
    moved = np.array([compose2d((5.0, -2.0, 0.7), p) for p in poses])
    assert evaluate(times, moved, rel).trans_mean == pytest.approx(0.0, abs=1e-9)
    # ...while 0.1 m forward added to every estimated step shows as 0.1 m of error.
    stretched = [poses[0]]
    for k in range(1, len(poses)):
        step = relative2d(poses[k - 1], poses[k])
        stretched.append(compose2d(stretched[-1], (step[0] + 0.1 / 3, step[1], step[2])))
    e = evaluate(times, np.array(stretched), rel)
    assert e.trans_mean == pytest.approx(0.1, abs=0.01) and e.count == len(rel)
    assert pose_at(times, poses, 100.0) is None  # no estimate near that time


def _room_drive_bag(tmp_path):
    """(a bag of the simulator's /scan and /odom: the mbot in a furnished 8 x 6 m room driving 15 s
    forward, turning, forward; the robot's final pose, spawned at (-2.5, -1.0, 0))."""
    import rosbag
    import rospy
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import LaserScan

    from mbot_slam_navigation.sim.sdf_world import World, Shape
    from mbot_slam_navigation.sim.simulation import Simulation
    from mbot_slam_navigation.transforms import yaw_to_quaternion
    from test_simulation import robot_spec

    world = World('room', [Shape('box', 0, 3.05, 0, 8.2, 0.1), Shape('box', 0, -3.05, 0, 8.2, 0.1),
                           Shape('box', 4.05, 0, 0, 0.1, 6.2), Shape('box', -4.05, 0, 0, 0.1, 6.2),
                           Shape('box', 1.5, 1.0, 0.4, 0.6, 0.6), Shape('circle', -1.0, 1.5, radius=0.3)])
    sim = Simulation(world, slip_stddev=0.02, seed=1)
    robot = sim.spawn('r', robot_spec(), (-2.5, -1.0, 0.0))
    bag_path = str(tmp_path / 'drive.bag')
    with rosbag.Bag(bag_path, 'w') as bag:
        for step in range(1500):  # 15 s: forward, a turn, forward
            sim.command('r', 0.3, 0.4 if 500 <= step < 800 else 0.0)
            sim.step()
            stamp = rospy.Time.from_sec(sim.time)
            if step % 5 == 0:
                odom = Odometry()
                odom.header.stamp = stamp
                ox, oy, oyaw = robot.drive.odom_pose
                odom.pose.pose.position.x, odom.pose.pose.position.y = ox, oy
                (odom.pose.pose.orientation.x, odom.pose.pose.orientation.y, odom.pose.pose.orientation.z,
                 odom.pose.pose.orientation.w) = yaw_to_quaternion(oyaw)
                bag.write('/odom', odom, stamp)
            if step % 10 == 0:
                s = robot.lasers[0].spec
                scan = LaserScan()
                scan.header.stamp, scan.header.frame_id = stamp, 'laser'
                scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max = \
                    s.angle_min, s.angle_increment, s.range_min, s.range_max
                scan.ranges = sim.scan(robot, robot.lasers[0]).tolist()
                bag.write('/scan', scan, stamp)
    return bag_path, robot.pose


@pytest.mark.parametrize('backend, params', [('rbpf', ['particles=5']), ('graph', ['loop_candidates=2'])])
def test_slam_offline_on_a_rosbag(tmp_path, backend, params):
    """A bag recorded from the simulator's topics (/scan, /odom) goes through slam_offline, with
    either backend and its own parameters."""
    from mbot_slam_navigation.slam.offline import main

    bag_path, final = _room_drive_bag(tmp_path)
    out = str(tmp_path / 'drive')
    extra = [a for p in params for a in ('--param', p)]
    assert main([bag_path, '-o', out, '--quiet', '--backend', backend, '--param', 'maxUrange=9.5',
                 '--param', 'maxRange=10', '--param', 'linearUpdate=0.2', '--param', 'angularUpdate=0.2'] + extra) == 0
    traj = np.loadtxt(out + '.traj')
    assert traj.shape[1] == 4 and len(traj) == 150
    # The map frame starts at the first odometry pose (the spawn pose's odom is 0): compare motion.
    true_motion = relative2d((-2.5, -1.0, 0.0), final)
    assert np.hypot(traj[-1, 1] - true_motion[0], traj[-1, 2] - true_motion[1]) < 0.1
    assert os.path.exists(out + '.pgm') and os.path.exists(out + '.yaml')


def test_slam_offline_takes_a_bags_range_from_its_scans(tmp_path):
    """Without maxUrange and maxRange, slam_offline takes the scans' range_max as the node does,
    not 80 m: beams without a return then clear no more than the sensor reaches."""
    import json

    from mbot_slam_navigation.slam.offline import main

    bag_path, _ = _room_drive_bag(tmp_path)
    out = str(tmp_path / 'drive')
    assert main([bag_path, '-o', out, '--quiet', '--param', 'linearUpdate=0.2', '--param', 'angularUpdate=0.2']) == 0
    with open(out + '.timing.json') as f:
        params = json.load(f)['params']
    from mbot_slam_navigation.slam.offline import read_rosbag
    sensor = read_rosbag(bag_path)[0].range_max
    assert sensor is not None and sensor < 80.0
    assert params['maxRange'] == pytest.approx(sensor) and params['maxUrange'] == pytest.approx(sensor)
    # given, they are kept
    assert main([bag_path, '-o', out, '--quiet', '--param', 'maxRange=10', '--param', 'linearUpdate=0.2',
                 '--param', 'angularUpdate=0.2']) == 0
    with open(out + '.timing.json') as f:
        params = json.load(f)['params']
    assert params['maxRange'] == 10.0 and params['maxUrange'] == pytest.approx(sensor)


def test_a_log_mapped_in_two_sessions_ends_where_one_run_does(tmp_path, capsys):
    """slam_offline --session-out on the first half, --session-in on the second: the second half
    joins the saved map (given the pose where the first ended, or found by matching) and its
    trajectory covers both halves; --localize tracks on the saved map."""
    from mbot_slam_navigation.slam.offline import main

    bag_path, final = _room_drive_bag(tmp_path)
    common = ['--quiet', '--param', 'maxUrange=9.5', '--param', 'maxRange=10', '--param', 'linearUpdate=0.2',
              '--param', 'angularUpdate=0.2']
    session = str(tmp_path / 'half')
    assert main([bag_path, '-o', str(tmp_path / 'one'), '--scans', '0:75', '--session-out', session] + common) == 0
    assert os.path.isfile(session + '.posegraph')
    end = np.loadtxt(str(tmp_path / 'one.traj'))[-1, 1:4]
    true_motion = relative2d((-2.5, -1.0, 0.0), final)
    for how, extra in (('pose', ['--start-pose', '%f,%f,%f' % tuple(end)]), ('matching', []),
                       ('localize', ['--start-pose', '%f,%f,%f' % tuple(end), '--localize'])):
        out = str(tmp_path / how)
        assert main([bag_path, '-o', out, '--scans', '75:', '--session-in', session] + extra + common) == 0, how
        traj = np.loadtxt(out + '.traj')
        assert len(traj) == (75 if how == 'localize' else 150), how
        assert np.hypot(traj[-1, 1] - true_motion[0], traj[-1, 2] - true_motion[1]) < 0.1, how
    # bad sessions: one message naming the file and what is wrong, exit status 2
    with open(session + '.posegraph', 'rb') as f:
        good = f.read()
    for name, content, message in (('missing', None, 'no such file'), ('truncated', good[:len(good) // 2], 'truncated'),
                                   ('image', b'P5\n2 2\n255\n\0\0\0\0', 'not a session')):
        path = str(tmp_path / name)
        if content is not None:
            with open(path + '.posegraph', 'wb') as f:
                f.write(content)
        with pytest.raises(SystemExit) as exit_:
            main([bag_path, '-o', str(tmp_path / 'x'), '--scans', '75:', '--session-in', path] + common)
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert path + '.posegraph' in err and message in err, err


def test_a_bag_recorded_live_gives_each_scan_the_odometry_at_its_stamp(tmp_path):
    """rosbag record writes messages as they arrive: a scan may come before the odometry of its
    own time, or long after it. Each scan gets the odometry interpolated at its stamp; scans
    outside the odometry's span are left out."""
    import rosbag
    import rospy
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import LaserScan

    from mbot_slam_navigation.slam.offline import read_rosbag
    from mbot_slam_navigation.transforms import yaw_to_quaternion

    def odom_at(t):  # 0.3 m/s along x, turning at 0.2 rad/s (yaw wraps past pi at the end)
        return 0.3 * t, 0.0, math.remainder(2.9 + 0.2 * t, 2 * math.pi)

    rng = np.random.default_rng(3)
    messages = []
    for k in range(200):  # odometry at 50 Hz over 4 s
        t = 0.02 * k
        msg = Odometry()
        msg.header.stamp = rospy.Time.from_sec(t)
        x, y, yaw = odom_at(t)
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        (msg.pose.pose.orientation.x, msg.pose.pose.orientation.y, msg.pose.pose.orientation.z,
         msg.pose.pose.orientation.w) = yaw_to_quaternion(yaw)
        messages.append(('/odom', msg, t))
    for k in range(45):  # scans at 10 Hz from 0.005 s to 4.405 s, the last 5 after the odometry ends
        t = 0.005 + 0.1 * k
        msg = LaserScan()
        msg.header.stamp = rospy.Time.from_sec(t)
        msg.angle_min, msg.angle_increment, msg.range_max = -math.pi, math.pi / 180, 10.0
        msg.ranges = [1.0] * 360
        # recorded up to 0.4 s early or late, as a busy machine's rosbag record does
        messages.append(('/scan', msg, t + rng.uniform(-0.4, 0.4)))
    path = str(tmp_path / 'live.bag')
    with rosbag.Bag(path, 'w') as bag:
        for topic, msg, t in sorted(messages, key=lambda m: m[2]):
            bag.write(topic, msg, rospy.Time.from_sec(max(t, 0.001)))
    scans = read_rosbag(path)
    assert [round(s.time, 3) for s in scans] == [round(0.005 + 0.1 * k, 3) for k in range(40)]
    for s in scans:
        x, y, yaw = odom_at(s.time)
        assert s.odom[0] == pytest.approx(x, abs=1e-6) and s.odom[1] == pytest.approx(y, abs=1e-6)
        assert abs(math.remainder(s.odom[2] - yaw, 2 * math.pi)) < 1e-6


def test_slam_offline_names_an_unknown_parameter_of_the_backend(tmp_path, capsys):
    """`particles` belongs to the particle filter: the graph backend refuses it by name."""
    from mbot_slam_navigation.slam.offline import main
    with pytest.raises(SystemExit) as e:
        main([os.path.join(DATA, 'tiny.clf'), '-o', str(tmp_path / 'x'), '--quiet', '--param', 'particles=5'])
    assert e.value.code == 2
    assert 'unknown graph SLAM parameter "particles"' in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([os.path.join(DATA, 'tiny.clf'), '-o', str(tmp_path / 'x'), '--quiet', '--backend', 'graph',
              '--param', 'loop_min_respons=0.5'])
    assert 'did you mean loop_min_response?' in capsys.readouterr().err


def test_graph_parameters_reach_the_core_and_bad_ones_are_refused():
    from mbot_slam_navigation import _core
    from mbot_slam_navigation.slam.backends import make_graph_params
    p = make_graph_params({'submap_nodes': 7, 'loop_min_response': 0.6, 'linearUpdate': 0.3})
    assert (p.submap_nodes, p.loop_min_response, p.linear_update) == (7, 0.6, 0.3)
    assert p.match_sigma == _core._GraphSlamParams().match_sigma and not p.background
    with pytest.raises(ValueError, match='loop_min_response'):
        make_graph_params({'loop_min_response': 2.0})
    with pytest.raises(ValueError, match='local_search_max_window'):
        make_graph_params({'local_search_max_window': 0.1})  # below local_search_window
    assert make_graph_params({'keep_trimmed_scans': 1}).keep_trimmed_scans is True


def test_the_filters_motion_noise_defaults_to_the_odometry_it_moves_with():
    """gmapping's srr, srt, str, stt on the wheels; a tenth of them on the scan-matched track (the
    default), unless the user gives them; what the user gives is kept whichever odometry."""
    from mbot_slam_navigation.slam.backends import make_params

    def noise(p):
        return (p.motion.srr, p.motion.srt, p.motion.str, p.motion.stt)

    assert noise(make_params({})) == pytest.approx((0.01, 0.02, 0.01, 0.02))
    assert noise(make_params({'scan_odometry': 0})) == pytest.approx((0.1, 0.2, 0.1, 0.2))
    assert noise(make_params({'srr': 0.05})) == pytest.approx((0.05, 0.02, 0.01, 0.02))
    assert noise(make_params({'scan_odometry': 0, 'stt': 0.3})) == pytest.approx((0.1, 0.2, 0.1, 0.3))
    with pytest.raises(ValueError, match='srt'):
        make_params({'srt': -0.1})


def test_the_graph_lists_its_chain_edges_as_the_relative_poses_of_its_nodes():
    from mbot_slam_navigation.slam.offline import run
    slam, _ = run(read_log(os.path.join(DATA, 'tiny.clf')), {'linearUpdate': 0.2, 'angularUpdate': 0.2},
                  progress=False, backend='graph')
    nodes, edges = slam.trajectory(), slam.edges()
    assert [(f, t) for f, t, *_ in edges] == [(k, k + 1) for k in range(len(nodes) - 1)]
    for f, t, x, y, theta, closure in edges:  # no closure in 3 scans: nothing moved the chain
        assert not closure
        assert np.allclose(relative2d(nodes[f, 1:4], nodes[t, 1:4]), (x, y, theta), atol=1e-9)
    assert slam.closures() == []


def test_offline_runs_read_the_nodes_parameters_with_the_nodes_defaults():
    """slam_offline and the node read one declaration (core/slam_config.h): the same defaults,
    except maxUrange and maxRange, which a log cannot take from its scans."""
    from mbot_slam_navigation import _core
    from mbot_slam_navigation.slam.backends import OFFLINE_MAX_RANGE, make_graph_params, make_params
    node, unknown = _core.read_slam_config({}, '/slam_gmapping', None, -1.0)
    assert unknown == [] and node.rbpf.matcher.max_urange == -1.0
    g, p = make_graph_params({}), make_params({})
    assert g.matcher.max_urange == OFFLINE_MAX_RANGE and p.matcher.max_range == OFFLINE_MAX_RANGE
    for key in ('local_map_nodes', 'local_prior_points', 'loop_min_response', 'submap_nodes', 'linear_update'):
        assert getattr(g, key) == pytest.approx(getattr(node.graph, key)), key
    for key in ('particles', 'ogain', 'best_switch_margin', 'linear_update', 'resample_threshold'):
        assert getattr(p, key) == pytest.approx(getattr(node.rbpf, key)), key
    assert (g.linear_update, p.linear_update) == (0.5, 1.0)  # a node every 0.5 m; gmapping's 1 m


def test_a_carmen_log_becomes_a_bag_that_slam_can_play(tmp_path):
    """The bag of a log: per scan, /tf odom -> base_link -> laser at the scan's stamp, then /scan,
    with the log's readings above range_max left as they are (out of range, REP 117)."""
    import rosbag
    from mbot_slam_navigation.slam.bags import write_scan_bag
    from mbot_slam_navigation.transforms import quaternion_to_yaw
    scans = read_log(os.path.join(DATA, 'tiny.clf'))
    path = str(tmp_path / 'tiny.bag')
    assert write_scan_bag(scans, path) == 3
    assert not os.path.exists(path + '.part')
    with rosbag.Bag(path) as bag:
        msgs = list(bag.read_messages())
    assert [m.topic for m in msgs] == ['/tf', '/scan'] * 3
    tf, scan = msgs[2].message, msgs[3].message  # the second scan
    odom, laser = tf.transforms
    assert (odom.header.frame_id, odom.child_frame_id, laser.header.frame_id, laser.child_frame_id) == (
        'odom', 'base_link', 'base_link', 'laser')
    q = odom.transform.rotation
    assert (odom.transform.translation.x, odom.transform.translation.y) == pytest.approx(scans[1].odom[:2])
    assert quaternion_to_yaw(q.x, q.y, q.z, q.w) == pytest.approx(scans[1].odom[2])
    assert laser.transform.translation.y == pytest.approx(scans[1].laser_pose[1], abs=1e-6)
    assert scan.header.stamp.to_sec() == pytest.approx(scans[1].time) and odom.header.stamp == scan.header.stamp
    assert scan.header.frame_id == 'laser' and scan.range_max == 80.0
    assert len(scan.ranges) == 5 and scan.angle_max == pytest.approx(math.pi / 2)
    first = msgs[1].message
    assert first.ranges[2] == pytest.approx(81.91)  # above range_max: no return, as the log meant


def test_corrections_as_the_robot_sees_them():
    """A rotation of map -> odom moves the robot by the rotation times its distance from the odom
    origin, not by how far the odom frame's origin moved; the robot's own motion between two
    publications is not a correction."""
    from mbot_slam_navigation.slam.bags import corrections_at_robot
    odom_times = np.array([0.0, 1.0, 2.0, 3.0])
    odom = np.array([(0.0, 0.0, 0.0), (10.0, 0.0, 0.0), (20.0, 0.0, 0.0), (30.0, 0.0, 0.0)])
    pubs = np.array([(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0),       # the robot drives: no correction
                     (2.0, 0.0, 0.0, 0.01),                              # 0.01 rad at 20 m from the origin
                     (3.0, -0.3, 0.0, 0.01)])                            # a 0.3 m shift back
    moves = corrections_at_robot(pubs, odom_times, odom)
    assert moves.shape == (3, 3)
    assert moves[0, 1] == pytest.approx(0.0)
    assert moves[1, 1] == pytest.approx(0.2, abs=0.001) and moves[1, 2] == pytest.approx(0.01)
    assert moves[2, 1] == pytest.approx(0.3) and moves[2, 0] == 3.0
    assert corrections_at_robot(pubs[:1], odom_times, odom).shape == (0, 3)


@pytest.mark.parametrize('backend', ['graph', 'rbpf'])
def test_run_fed_at_a_rate_keeps_each_scans_pose_as_processed(backend):
    """As `rosbag play -r 0.5` feeds a node: the run takes at least the log's span / 0.5, each
    scan's pose as it was processed (what a node publishes) is kept, and the CPU seconds count the
    whole process (the graph's closure thread included)."""
    from mbot_slam_navigation.slam.offline import run
    scans = read_log(os.path.join(DATA, 'tiny.clf'))
    span = scans[-1].time - scans[0].time
    online = []
    t0 = time.monotonic()
    slam, cpu = run(scans, {}, progress=False, backend=backend, rate=0.5, background=True, online=online)
    assert time.monotonic() - t0 >= span / 0.5 - 0.02
    assert len(online) == len(scans) and 0.0 < cpu
    # The map frame starts at the first scan's odometry, (0, 0, 0) in tiny.clf.
    assert online[0] == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    flat = []
    run(scans, {}, progress=False, backend=backend, online=flat)
    assert np.allclose(flat, online, atol=1e-6)  # pacing changes when, not what


@pytest.mark.parametrize('name, content, reader, error, message', [
    ('photo.clf', bytes(range(256)) * 4, read_log, CarmenError,
     r'photo.clf: not a CARMEN log: expected text lines .*found binary data \(first bytes 00 01 02'),
    ('log.clf.bz2', b'not bzip2 at all', read_log, CarmenError, r'log.clf.bz2: cannot be read as a bzip2 file'),
    ('run.clf', b'#ROSBAG V2.0\n' + bytes(100), read_log, CarmenError, 'is a rosbag, not a CARMEN log'),
    ('run.bag', b'FLASER 3 1 2 3 0 0 0 0 0 0 1.0\n', read_rosbag, BagError,
     r"run.bag: not a rosbag: expected the header \"#ROSBAG V2.0\", found 'FLASER"),
    ('cut.bag', b'#ROSBAG V2.0\n' + bytes(50), read_rosbag, BagError, 'cut.bag: the bag cannot be read'),
])
def test_files_that_are_no_log_say_what_was_expected_and_found(tmp_path, name, content, reader, error, message):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(error, match=message):
        reader(str(path))
