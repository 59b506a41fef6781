#!/usr/bin/env python3
"""Simulator benchmark.

1. Laser rays per second of the C++ ray caster (360-beam scans from 500 random free poses, one
   core, median of 5 runs), in the home world and in a floor plan of 600 x 600 pixels at 0.05 m
   (30 m x 30 m, a map_server YAML world: a grid of rooms with doors and furniture, seeded,
   written to bench/out/floor600.yaml), and in each map YAML of BENCH_SIM_MAPS (colon-separated).
2. How long such a map takes to load as a world (load_world + Simulation, median of 5).
3. Real-time factor of the gazebo_sim node, headless, with the mbot driving in a circle (360-beam
   laser at 10 Hz, drive at 100 Hz, odometry at 50 Hz, /clock at 100 Hz), with subscribers on
   /scan, /odom, /clock and /tf as a SLAM stack would have: simulated seconds per wall second over
   20 s of wall time, real_time_factor:=0 (as fast as possible); median of 3 runs; in the home and
   in the floor plan.
"""
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import time

import numpy as np

from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.sim.simulation import Simulation
from mbot_slam_navigation.sim.urdf_robot import parse_urdf

PKG = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
WORLD = os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world')
XACRO = [os.path.join(PKG, 'scripts', 'xacro'), os.path.join(PKG, 'urdf', 'xacro', 'robot.xacro')]


FLOOR = os.path.join(PKG, 'bench', 'out', 'floor600.yaml')
START = (2.5, 2.5, 0.0)  # [m] the spawn pose in the floor plan: the middle of the first room


def floor_plan(path: str = FLOOR, pixels: int = 600, resolution: float = 0.05, seed: int = 1) -> str:
    """A building's floor plan as a map_server map: rooms of 5 m on a grid, walls 0.15 m thick, a
    door of 1 m in every wall between two rooms, a few pieces of furniture per room."""
    import cv2
    from mbot_slam_navigation.maps.map_io import save_map
    rng = np.random.default_rng(seed)
    size = pixels * resolution
    img = np.zeros((pixels, pixels), np.int8)  # rows from the lowest y, as save_map takes them
    px = lambda m: int(round(m / resolution))  # noqa: E731
    wall = px(0.15)
    for k in range(0, int(size / 5.0) + 1):
        a = min(px(5.0 * k), pixels - wall)
        img[a:a + wall, :] = 100
        img[:, a:a + wall] = 100
    for i in range(int(size / 5.0)):
        for j in range(int(size / 5.0)):
            x0, y0 = px(5.0 * i), px(5.0 * j)
            if i > 0:  # a door in the west wall of room (i, j)
                d = y0 + px(rng.uniform(1.0, 3.0))
                img[d:d + px(1.0), x0:x0 + wall] = 0
            if j > 0:  # and in its south wall
                d = x0 + px(rng.uniform(1.0, 3.0))
                img[y0:y0 + wall, d:d + px(1.0)] = 0
            for _ in range(rng.integers(1, 4)):  # furniture, away from the doors
                w, h = px(rng.uniform(0.4, 1.2)), px(rng.uniform(0.4, 1.2))
                cx, cy = x0 + px(rng.uniform(1.2, 3.8)), y0 + px(rng.uniform(1.2, 3.8))
                cv2.rectangle(img, (cx, cy), (cx + w, cy + h), 100, -1)
    img[px(1.5):px(3.5), px(1.5):px(3.5)] = 0  # the spawn place is clear
    os.makedirs(os.path.dirname(path), exist_ok=True)
    save_map(path[:-5], img, resolution, (0.0, 0.0, 0.0))
    return path


def free_poses(sim, n, bounds, seed=0):
    rng = np.random.default_rng(seed)
    poses = []
    while len(poses) < n:
        p = (rng.uniform(bounds[0], bounds[2]), rng.uniform(bounds[1], bounds[3]), rng.uniform(-math.pi, math.pi))
        if not sim.geometry.overlaps([np.array(p[:2]) + d for d in ((0.2, 0.2), (-0.2, 0.2), (-0.2, -0.2), (0.2, -0.2))]):
            poses.append(p)
    return poses


def load_seconds(world_file):
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        Simulation(load_world(world_file))
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def rays_per_second(world_file=WORLD, start=(0.0, 0.0, 0.0), bounds=None):
    """`bounds` (xmin, ymin, xmax, ymax) [m] of the poses; default the world's."""
    urdf = subprocess.run(XACRO, check=True, capture_output=True, text=True).stdout
    world = load_world(world_file)
    sim = Simulation(world)
    robot = sim.spawn('robot', parse_urdf(urdf), start)
    laser = robot.lasers[0]
    poses = free_poses(sim, 500, bounds or world.bounds())
    rates = []
    for _ in range(5):
        t0 = time.perf_counter()
        for p in poses:
            sim.set_pose('robot', p)
            sim.scan(robot, laser)
        rates.append(len(poses) * laser.spec.samples / (time.perf_counter() - t0))
    return statistics.median(rates)


def node_real_time_factor(world_file=WORLD, start=(-2.0, -3.5), wall_seconds=20.0):
    import rospy
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import LaserScan
    from tf2_msgs.msg import TFMessage

    env = dict(os.environ, ROS_MASTER_URI='http://localhost:11399')
    os.environ['ROS_MASTER_URI'] = env['ROS_MASTER_URI']
    procs = [subprocess.Popen(['roscore', '-p', '11399'], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, preexec_fn=os.setsid)]
    time.sleep(3.0)
    try:
        rospy.init_node('bench_sim', anonymous=True, disable_signals=True)
        rospy.set_param('/use_sim_time', True)
        rospy.set_param('/robot_description', subprocess.run(XACRO, check=True, capture_output=True, text=True).stdout)
        procs.append(subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'gazebo_sim', '_world_name:=' + world_file,
                                       '_real_time_factor:=0', '_cmd_vel_timeout:=0', '_gui:=false',
                                       'robot/laser/scan:=/scan'],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      preexec_fn=os.setsid))
        subprocess.run(['rosrun', 'mbot_slam_navigation', 'spawn_model', '-urdf', '-model', 'robot', '-param',
                        'robot_description', '-x', str(start[0]), '-y', str(start[1]), 'robot/laser/scan:=/scan'],
                       env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        counts = {'scan': 0, 'odom': 0, 'clock': 0, 'tf': 0}
        last_clock = [0.0]

        def count(key):
            def cb(msg):
                counts[key] += 1
                if key == 'clock':
                    last_clock[0] = msg.clock.to_sec()
            return cb
        rospy.Subscriber('/scan', LaserScan, count('scan'), queue_size=100)
        rospy.Subscriber('/odom', Odometry, count('odom'), queue_size=100)
        rospy.Subscriber('/clock', Clock, count('clock'), queue_size=100)
        rospy.Subscriber('/tf', TFMessage, count('tf'), queue_size=100)
        pub = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
        t = Twist()
        t.linear.x, t.angular.z = 0.3, 0.3  # a 1 m radius circle: in the living room, in the first room
        pub.publish(t)
        time.sleep(3.0)
        c0, w0, n0 = last_clock[0], time.monotonic(), dict(counts)
        time.sleep(wall_seconds)
        c1, w1 = last_clock[0], time.monotonic()
        rates = {k: (counts[k] - n0[k]) / (c1 - c0) for k in counts}
        return (c1 - c0) / (w1 - w0), rates
    finally:
        for p in reversed(procs):
            os.killpg(p.pid, signal.SIGINT)
            p.wait()


def node_runs(world_file, start, name):
    runs = []
    for i in range(3):
        # Each run in a fresh process: a rospy node cannot re-register with a new master.
        out = subprocess.run([sys.executable, os.path.abspath(__file__), '--node-run', world_file, str(start[0]),
                              str(start[1])], check=True, capture_output=True, text=True).stdout
        rtf, rates = json.loads(out.strip().splitlines()[-1])
        print('%s run %d: real-time factor %.1f; received per simulated second: %s'
              % (name, i + 1, rtf, ', '.join('%s %.1f' % kv for kv in sorted(rates.items()))), flush=True)
        runs.append(rtf)
    return statistics.median(runs)


def main():
    floor = floor_plan()
    rays = rays_per_second(bounds=(-7.4, -5.9, 4.4, 3.5))  # inside the home's outer walls
    print(json.dumps(dict(benchmark='sim', metric='laser ray casting, home world', value=rays, unit='rays/s',
                          target='>= 5e6', note='median of 5, one core, C++ core via binding')))
    maps = [('floor plan 600 x 600 px at 0.05 m', floor, START)]
    maps += [(os.path.basename(m), m, (0.0, 0.0, 0.0)) for m in os.environ.get('BENCH_SIM_MAPS', '').split(':') if m]
    for name, path, start in maps:
        print(json.dumps(dict(benchmark='sim', metric='load as a world, ' + name, value=load_seconds(path), unit='s',
                              target='< 1', note='median of 5: load_world + Simulation')))
        print(json.dumps(dict(benchmark='sim', metric='laser ray casting, ' + name, value=rays_per_second(path, start),
                              unit='rays/s', note='median of 5, one core; grid walked cell by cell')))
    print(json.dumps(dict(benchmark='sim', metric='gazebo_sim real-time factor, home world',
                          value=node_runs(WORLD, (-2.0, -3.5), 'home'),
                          unit='x real time', target='>= 100', note='median of 3 x 20 s wall, rtf:=0, driving')))
    print(json.dumps(dict(benchmark='sim', metric='gazebo_sim real-time factor, floor plan 600 x 600 px',
                          value=node_runs(floor, START, 'floor plan'),
                          unit='x real time', target='>= 100', note='median of 3 x 20 s wall, rtf:=0, driving')))


if __name__ == '__main__':
    if sys.argv[1:2] == ['--node-run']:
        print(json.dumps(node_real_time_factor(sys.argv[2], (float(sys.argv[3]), float(sys.argv[4])))))
    else:
        main()
