#!/usr/bin/env python3
"""Simulator benchmark (issue: 2D simulator).

1. Laser rays per second of the C++ ray caster in the home world (360-beam scans from 500 random
   free poses, one core, median of 5 runs).
2. Real-time factor of the gazebo_sim node, headless, in the home world with the mbot driving in
   a circle (360-beam laser at 10 Hz, drive at 100 Hz, odometry at 50 Hz, /clock at 100 Hz), with
   subscribers on /scan, /odom, /clock and /tf as a SLAM stack would have: simulated seconds per
   wall second over 20 s of wall time, real_time_factor:=0 (as fast as possible); median of 3 runs.
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


def rays_per_second():
    urdf = subprocess.run(XACRO, check=True, capture_output=True, text=True).stdout
    sim = Simulation(load_world(WORLD))
    robot = sim.spawn('robot', parse_urdf(urdf), (0.0, 0.0, 0.0))
    laser = robot.lasers[0]
    rng = np.random.default_rng(0)
    poses = []
    while len(poses) < 500:
        p = (rng.uniform(-7.4, 4.4), rng.uniform(-5.9, 3.5), rng.uniform(-math.pi, math.pi))
        if not sim.geometry.overlaps([np.array(p[:2]) + d for d in ((0.2, 0.2), (-0.2, 0.2), (-0.2, -0.2), (0.2, -0.2))]):
            poses.append(p)
    rates = []
    for _ in range(5):
        t0 = time.perf_counter()
        for p in poses:
            sim.set_pose('robot', p)
            sim.scan(robot, laser)
        rates.append(len(poses) * laser.spec.samples / (time.perf_counter() - t0))
    return statistics.median(rates)


def node_real_time_factor(wall_seconds=20.0):
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
        procs.append(subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'gazebo_sim', '_world_name:=' + WORLD,
                                       '_real_time_factor:=0', '_cmd_vel_timeout:=0', '_gui:=false',
                                       'robot/laser/scan:=/scan'],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      preexec_fn=os.setsid))
        subprocess.run(['rosrun', 'mbot_slam_navigation', 'spawn_model', '-urdf', '-model', 'robot', '-param',
                        'robot_description', '-x', '-2', '-y', '-3.5', 'robot/laser/scan:=/scan'],
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
        t.linear.x, t.angular.z = 0.3, 0.3  # a 1 m radius circle in the living room
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


def main():
    rays = rays_per_second()
    print(json.dumps(dict(benchmark='sim', metric='laser ray casting, home world', value=rays, unit='rays/s',
                          target='>= 5e6', note='median of 5, one core, C++ core via binding')))
    runs = []
    for i in range(3):
        # Each run in a fresh process: a rospy node cannot re-register with a new master.
        out = subprocess.run([sys.executable, os.path.abspath(__file__), '--node-run'], check=True,
                             capture_output=True, text=True).stdout
        rtf, rates = json.loads(out.strip().splitlines()[-1])
        print('run %d: real-time factor %.1f; received per simulated second: %s'
              % (i + 1, rtf, ', '.join('%s %.1f' % kv for kv in sorted(rates.items()))), flush=True)
        runs.append(rtf)
    print(json.dumps(dict(benchmark='sim', metric='gazebo_sim real-time factor, home world', value=statistics.median(runs),
                          unit='x real time', target='>= 100', note='median of 3 x 20 s wall, rtf:=0, driving')))


if __name__ == '__main__':
    if sys.argv[1:] == ['--node-run']:
        print(json.dumps(node_real_time_factor()))
    else:
        main()
