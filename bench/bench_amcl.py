#!/usr/bin/env python3
"""amcl: filter update time, tracking accuracy on the car tutorial's map, and global localization
in the home world.

ROS-free: this package's simulator (sim/simulation.py) drives the robot on ground truth along a
route (RouteDriver) and feeds odometry and scans to the same Localizer the amcl node uses.
- update time: motion + sensor + resample, 500 and 5000 particles, a 360-beam scan; laser_max_beams
  30 (amcl_diff.launch) and 360 (every beam). Median of 30 updates, 3 runs. Target: 5000 in < 10 ms.
- tracking: the car on maps/map.yaml (made by slam_gmapping) with launch/amcl_diff.launch as the node reads it, started
  at its true pose; position error of every estimate against ground truth.
- global localization: the mbot in the home world (perfect map), particles over all free space,
  driving the home tour; time and distance until the estimate is within 0.2 m and stays there.
- kidnap: the car tracking on maps/map.yaml is carried 3 m into the next room (as set_model_state
  does) and drives on; how long until amcl says it is lost (FitMonitor, the node's warning), and
  until the estimate is back within 0.3 m for good: with recovery_alpha_slow/fast 0.001/0.1 (ROS's
  suggested values) amcl alone, and with amcl_diff.launch's 0/0 by global_localization called when
  it says it is lost. Target (issue 19): recovered within 30 s simulated.
Prints JSON result lines (see run_all.py) and writes bench/out/amcl_global.png (particles over the
map at the start and when converged, and the path).
"""
import json
import math
import os
import statistics
import subprocess
import sys
import time

import cv2
import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.launch_files import node_params
from mbot_slam_navigation.maps.map_io import load_map
from mbot_slam_navigation.nav.localizer import Localizer
from mbot_slam_navigation.route_driver import HOME_TOUR, RouteDriver
from mbot_slam_navigation.sim.ground_truth import rasterize
from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.sim.simulation import Simulation
from mbot_slam_navigation.sim.urdf_robot import parse_urdf

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(PKG, 'bench', 'out')
ROS_EXAMPLE_ALPHAS = dict(alpha1=0.2, alpha2=0.2, alpha3=0.8, alpha4=0.2)  # amcl_diff.launch in ROS, verbatim


def amcl_diff():
    """(core params, node settings) exactly as the amcl node reads launch/amcl_diff.launch."""
    from mbot_slam_navigation.nav.amcl import read_parameters
    from mbot_slam_navigation.nav.params import ParamReader
    r = ParamReader(node_params(os.path.join(PKG, 'launch', 'amcl_diff.launch'), '/amcl'), '/amcl', print)
    return read_parameters(r)


# wall.world: through all three rooms (the car's route when the map was made, shortened).
WALL_ROUTE = [(0.0, 3.4), (-3.2, 3.6), (-3.2, -3.6), (-3.2, 3.6), (0.0, 3.4), (0.0, -3.6), (2.6, -4.2),
              (4.2, -4.2), (4.2, -1.0), (3.4, 3.6)]


def emit(metric, value, unit, target='', note=''):
    print(json.dumps({'benchmark': 'amcl', 'metric': metric, 'value': value, 'unit': unit, 'target': target,
                      'note': note}), flush=True)


def make_pf(map_data, resolution, origin, seed=1, **overrides):
    p = amcl_diff()[0]
    for k, v in overrides.items():
        setattr(p, k, v)
    pf = _core._Amcl(p, seed)
    pf.set_map(_core._AmclMap(map_data, resolution, tuple(origin[:2])))
    return pf


def xacro(path):
    return subprocess.run([os.path.join(PKG, 'scripts', 'xacro'), path], check=True, capture_output=True,
                          text=True).stdout


class Drive:
    """The simulator with one robot following a route on ground truth; yields (odom pose, scan)."""

    def __init__(self, world_file, urdf_file, start, route, seed=0, slip=0.02):
        self.sim = Simulation(load_world(world_file), slip_stddev=slip, seed=seed)
        self.robot = self.sim.spawn('robot', parse_urdf(xacro(urdf_file)), start)
        self.laser = self.robot.lasers[0]
        self.driver = RouteDriver(route)
        self.distance = 0.0

    def scans(self, max_time=900.0):
        spec = self.laser.spec
        period = 1.0 / spec.update_rate
        next_scan = 0.0
        last = self.robot.pose
        while not self.driver.done and self.sim.time < max_time:
            c = self.driver.command(self.robot.pose)
            if c is not None:
                self.sim.command('robot', *c)
            self.sim.step()
            p = self.robot.pose
            self.distance += math.hypot(p[0] - last[0], p[1] - last[1])
            last = p
            if self.sim.time + 1e-9 >= next_scan:
                next_scan += period
                odom = tuple(float(v) for v in self.robot.drive.odom_pose)
                yield odom, self.sim.scan(self.robot, self.laser)


def laser_args(drive):
    s = drive.laser.spec
    # The lasers here are mounted level and forward: base-frame angles are the laser's plus its yaw.
    return s.angle_min + s.pose_in_base[2], s.angle_increment, s.range_min, s.range_max, s.pose_in_base[:2]


def update_time():
    m = load_map(os.path.join(PKG, 'maps', 'map.yaml'))
    drive = Drive(os.path.join(PKG, 'worlds', 'wall.world'), os.path.join(PKG, 'urdf', 'myrobot.xacro'),
                  (0.0, 0.0, 0.0), WALL_ROUTE)
    scans = []
    for odom, ranges in drive.scans(max_time=40.0):
        scans.append((odom, ranges))
    # A 360-beam scan: the car's 720 beams over 240 degrees, every other one.
    a0, inc, rmin, rmax, lxy = laser_args(drive)
    for particles in (500, 5000):
        for beams in (30, 360):
            runs = []
            for run in range(3):
                pf = make_pf(m.data, m.resolution, m.origin, seed=run, min_particles=particles,
                             max_particles=particles, max_beams=beams)
                pf.init_gaussian(np.zeros(3), np.diag([0.01, 0.01, 0.01]))
                times = []
                for k in range(1, 31):
                    (o0, _), (o1, ranges) = scans[4 * (k - 1)], scans[4 * k]
                    t = time.perf_counter()
                    pf.motion_update(np.asarray(o0), np.asarray(o1))
                    pf.sensor_update(a0, 2 * inc, rmin, rmax, ranges[::2], np.array([lxy[0], lxy[1], 0.0]))
                    pf.resample()
                    times.append(time.perf_counter() - t)
                runs.append(statistics.median(times) * 1000)
            emit('update %d particles, %d of 360 beams' % (particles, beams), statistics.median(runs), 'ms',
                 '< 10' if particles == 5000 else '', 'runs %s' % ', '.join('%.2f' % r for r in runs))


def tracking(label='amcl_diff.launch', **overrides):
    m = load_map(os.path.join(PKG, 'maps', 'map.yaml'))
    settings = amcl_diff()[1]
    results = []
    for seed in range(3):
        drive = Drive(os.path.join(PKG, 'worlds', 'wall.world'), os.path.join(PKG, 'urdf', 'myrobot.xacro'),
                      (0.0, 0.0, 0.0), WALL_ROUTE, seed=seed)
        pf = make_pf(m.data, m.resolution, m.origin, seed=seed, **overrides)
        pf.init_gaussian(np.zeros(3), np.diag([0.25, 0.25, (math.pi / 12) ** 2]))
        loc = Localizer(pf, settings['update_min_d'], settings['update_min_a'], settings['resample_interval'])
        a0, inc, rmin, rmax, lxy = laser_args(drive)
        errors = []
        for odom, ranges in drive.scans():
            if loc.update(odom, a0, inc, rmin, rmax, ranges, lxy):
                est = loc.estimate()[0]
                truth = drive.robot.pose
                errors.append(math.hypot(est[0] - truth[0], est[1] - truth[1]))
        settled = errors[5:]  # the first updates shrink the initial spread
        results.append((max(settled), statistics.mean(settled), len(errors), drive.distance))
        print('tracking run %d: %d updates over %.1f m, error mean %.3f m, max %.3f m (after the first 5)'
              % (seed, len(errors), drive.distance, results[-1][1], results[-1][0]), flush=True)
    emit('tracking error, max (car, map.yaml, %s)' % label, statistics.median(r[0] for r in results), 'm',
         '< 0.15', 'median of 3 runs; runs %s' % ', '.join('%.3f' % r[0] for r in results))
    emit('tracking error, mean (%s)' % label, statistics.median(r[1] for r in results), 'm', '', 'median of 3 runs')


def tracking_ros_alphas():
    """The same with ROS's example alphas taken verbatim by the corrected model."""
    tracking('ROS example alphas verbatim', **ROS_EXAMPLE_ALPHAS)


def global_localization():
    world = os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world')
    data, origin = rasterize(load_world(world), 0.05)
    settings = amcl_diff()[1]
    results = []
    picture = None
    for seed in range(3):
        drive = Drive(world, os.path.join(PKG, 'urdf', 'xacro', 'robot.xacro'), (0.0, 0.0, 0.0), HOME_TOUR * 2,
                      seed=seed)
        pf = make_pf(data, 0.05, origin, seed=seed, max_particles=20000, min_particles=500,
                     recovery_alpha_slow=0.001, recovery_alpha_fast=0.1)
        pf.init_uniform()
        start_cloud = pf.particles()
        loc = Localizer(pf, settings['update_min_d'], settings['update_min_a'], settings['resample_interval'])
        a0, inc, rmin, rmax, lxy = laser_args(drive)
        converged_at, path = None, []
        for odom, ranges in drive.scans(max_time=600.0):
            path.append(drive.robot.pose)
            if not loc.update(odom, a0, inc, rmin, rmax, ranges, lxy):
                continue
            est = loc.estimate()[0]
            truth = drive.robot.pose
            err = math.hypot(est[0] - truth[0], est[1] - truth[1])
            if err <= 0.2:
                if converged_at is None:
                    converged_at = (drive.sim.time, drive.distance, pf.particles())
            else:
                converged_at = None  # must stay within 0.2 m from then on
        if converged_at is None:
            print('global localization run %d: not converged in %.0f s' % (seed, drive.sim.time), flush=True)
            results.append((math.inf, math.inf))
            continue
        results.append(converged_at[:2])
        print('global localization run %d: within 0.2 m for good after %.1f s and %.1f m' % (seed, *converged_at[:2]),
              flush=True)
        if picture is None:
            picture = (start_cloud, converged_at[2], path)
    emit('global localization, home: time to converge', statistics.median(r[0] for r in results), 's (sim)', '',
         '20000 particles; runs %s' % ', '.join('%.1f' % r[0] for r in results))
    emit('global localization, home: distance to converge', statistics.median(r[1] for r in results), 'm', '',
         'runs %s' % ', '.join('%.1f' % r[1] for r in results))
    if picture:
        draw(data, origin, *picture)


KIDNAP_RUNS = 12  # each about a second: enough runs to say how often, not only how long


def kidnap():
    m = load_map(os.path.join(PKG, 'maps', 'map.yaml'))
    settings = amcl_diff()[1]
    carry_at, carry = 20.0, (3.0, 0.0)   # [s simulated], [m]: from the middle room into the right one
    for label, overrides, relocalize, search in (
            ('recovery_alpha 0.001/0.1', dict(recovery_alpha_slow=0.001, recovery_alpha_fast=0.1), False, 0.0),
            ('amcl_diff.launch + global_localization when lost', {}, True, 0.0),
            ('amcl_diff.launch, recovery_search_radius 3 m (the default)', {}, False, 3.0)):
        detected, recovered = [], []
        for seed in range(KIDNAP_RUNS):
            drive = Drive(os.path.join(PKG, 'worlds', 'wall.world'), os.path.join(PKG, 'urdf', 'myrobot.xacro'),
                          (0.0, 0.0, 0.0), WALL_ROUTE * 2, seed=seed)
            pf = make_pf(m.data, m.resolution, m.origin, seed=seed, **overrides)
            pf.init_gaussian(np.zeros(3), np.diag([0.01, 0.01, 0.01]))
            loc = Localizer(pf, settings['update_min_d'], settings['update_min_a'], settings['resample_interval'],
                            search_radius=search)
            a0, inc, rmin, rmax, lxy = laser_args(drive)
            carried = lost_at = back_at = None
            for odom, ranges in drive.scans(max_time=carry_at + 180.0):
                t = drive.sim.time
                if carried is None and t >= carry_at:
                    x, y, yaw = drive.robot.pose
                    for dx in (carry[0], -carry[0]):  # into whichever neighbouring room is free
                        try:
                            drive.sim.set_pose('robot', (x + dx, y, yaw))
                            if not drive.sim.geometry.overlaps(drive.robot.drive.footprint_in_world(), 0):
                                break
                        except Exception:  # noqa: BLE001
                            continue
                    carried = t
                if not loc.update(odom, a0, inc, rmin, rmax, ranges, lxy):
                    continue
                if carried is None:
                    continue
                if loc.fit_change == 'lost' and lost_at is None:
                    lost_at = t - carried
                    if relocalize:
                        pf.init_uniform()
                        loc.reinitialized()
                est, truth = loc.estimate()[0], drive.robot.pose
                if math.hypot(est[0] - truth[0], est[1] - truth[1]) <= 0.3:
                    back_at = back_at if back_at is not None else t - carried
                else:
                    back_at = None
            detected.append(lost_at if lost_at is not None else math.inf)
            recovered.append(back_at if back_at is not None else math.inf)
            print('kidnap (%s) run %d: lost noticed after %s s, back within 0.3 m for good after %s s'
                  % (label, seed, '%.1f' % lost_at if lost_at is not None else 'never',
                     '%.1f' % back_at if back_at is not None else 'never'), flush=True)
        emit('kidnap 3 m, %s: noticed after' % label, statistics.median(detected), 's (sim)', '',
             'runs %s' % ', '.join('%.1f' % d for d in detected))
        emit('kidnap 3 m, %s: recovered after' % label, statistics.median(recovered), 's (sim)', '<= 30',
             '%d of %d runs within 30 s; runs %s' % (sum(r <= 30.0 for r in recovered), len(recovered),
                                                      ', '.join('%.1f' % r for r in recovered)))


def draw(data, origin, start, converged, path):
    img = np.where(data >= 65, 0, np.where(data == 0, 255, 205)).astype(np.uint8)
    img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)

    def px(x, y):
        return int((x - origin[0]) / 0.05), int((y - origin[1]) / 0.05)

    for x, y, *_ in start[::10]:
        cv2.circle(img, px(x, y), 0, (200, 160, 120), -1)
    for x, y, *_ in path[::20]:
        cv2.circle(img, px(x, y), 0, (0, 160, 0), -1)
    for x, y, *_ in converged:
        cv2.circle(img, px(x, y), 1, (0, 0, 255), -1)
    os.makedirs(OUT, exist_ok=True)
    cv2.imwrite(os.path.join(OUT, 'amcl_global.png'), cv2.resize(img[::-1], None, fx=3, fy=3,
                                                                    interpolation=cv2.INTER_NEAREST))


if __name__ == '__main__':
    which = sys.argv[1:] or ['update_time', 'tracking', 'tracking_ros_alphas', 'global_localization', 'kidnap']
    for name in which:
        globals()[name]()
