#!/usr/bin/env python3
"""slam_gmapping in the simulated home: the map's walls lie on the true walls and map -> base
follows ground truth while the robot drives a fixed route."""
import math
import os
import subprocess
import threading
import time
import unittest

import numpy as np
import rospkg
import rospy
import rostest
from std_msgs.msg import Float64
import tf2_ros
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from nav_msgs.srv import GetMap
from sensor_msgs.msg import LaserScan

from mbot_slam_navigation.route_driver import LIVING_ROOM_LOOPS, RouteDriver
from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, occupied_points
from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.transforms import quaternion_to_yaw

class SlamHomeTest(unittest.TestCase):
    def test_map_and_pose_follow_the_truth(self):
        world = load_world(os.path.join(rospkg.RosPack().get_path('mbot_slam_navigation'), 'worlds',
                                        'mbot_sim_gazebo_navigation.world'))
        truth = {}
        rospy.Subscriber('/base_pose_ground_truth', Odometry, lambda m: truth.update(pose=m.pose.pose, stamp=m.header.stamp))
        cmd = rospy.Publisher('/cmd_vel', Twist, queue_size=5)
        tf_buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(tf_buffer)
        rospy.wait_for_message('/map', OccupancyGrid, timeout=60.0)

        errors = []
        rate = rospy.Rate(20)
        last_check = rospy.Time(0)
        driver = RouteDriver(LIVING_ROOM_LOOPS)
        deadline = rospy.Time.now() + rospy.Duration(600.0)
        while not rospy.is_shutdown() and not driver.done:
            self.assertLess(rospy.Time.now(), deadline, 'route not done; at waypoint %d' % driver.index)
            p, stamp = truth.get('pose'), truth.get('stamp')
            if p is None:
                rate.sleep()
                continue
            x, y = p.position.x, p.position.y
            yaw = quaternion_to_yaw(p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w)
            c = driver.command((x, y, yaw))
            if c is None:
                break
            t = Twist()
            t.linear.x, t.angular.z = c
            cmd.publish(t)
            if rospy.Time.now() - last_check > rospy.Duration(1.0):
                last_check = rospy.Time.now()
                try:
                    # at the ground truth's own time, so that latency does not count as error
                    tf = tf_buffer.lookup_transform('map', 'base_footprint', stamp, rospy.Duration(0.5))
                    errors.append(math.hypot(tf.transform.translation.x - x, tf.transform.translation.y - y))
                except tf2_ros.TransformException:
                    pass
            rate.sleep()
        cmd.publish(Twist())
        rospy.sleep(3.0)  # one more map update after the last scans
        msg = rospy.wait_for_message('/map', OccupancyGrid, timeout=30.0)

        self.assertGreater(len(errors), 20)
        rospy.loginfo('map -> base_footprint vs ground truth: max %.3f m, mean %.3f m', max(errors), np.mean(errors))
        self.assertLess(max(errors), 0.1, 'map -> base_footprint off ground truth by up to %.3f m' % max(errors))
        d = distance_to_surfaces(world, occupied_points(msg))
        self.assertGreater(len(d), 500, 'too few occupied cells: %d' % len(d))
        rospy.loginfo('wall distances: median %.3f m, 95%% %.3f m, max %.3f m over %d cells',
                      np.median(d), np.percentile(d, 95), d.max(), len(d))
        # Occupied cells are 5 cm squares whose centres lie up to half a diagonal off the surface.
        self.assertLess(np.percentile(d, 95), 0.1, 'walls off the true walls: 95th percentile %.3f m' % np.percentile(d, 95))
        self.assertLess(np.median(d), 0.05)
        served = rospy.ServiceProxy('/dynamic_map', GetMap)().map
        self.assertEqual((served.info.width, served.info.height), (msg.info.width, msg.info.height))
        self.assertEqual(served.header.frame_id, 'map')

    def test_a_bad_parameter_stops_the_node_with_its_name(self):
        for arg, message in (('_backend:=particles',
                              "/param_check/backend must be 'graph' (pose graph) or 'rbpf' (particle filter), got "
                              "'particles'"),
                             ('_scan_queue_size:=0', '/param_check/scan_queue_size must be >= 1, got 0')):
            with self.subTest(arg=arg):
                out = subprocess.run(['rosrun', 'mbot_slam_navigation', 'slam_gmapping', '__name:=param_check', arg,
                                      'scan:=/param_check/scan', 'map:=/param_check/map',
                                      'dynamic_map:=/param_check/dynamic_map'],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
                self.assertEqual(out.returncode, 1, out.stdout)
                self.assertIn(message, out.stdout)

    def test_tutorial_typo_and_bad_scans_get_warnings(self):
        # A second instance, started as the tutorial does (~base_link, a typo for ~base_frame), in
        # frames of its own, fed by this test: the warnings a user reads in the terminal. It runs the
        # particle filter (the launch's instance runs the default pose graph), so both backends
        # serve the node's topics here.
        ns = '/tc'
        proc = subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'slam_gmapping', '__name:=typo_check',
                                 '_base_link:=base_footprint', '_base_frame:=tc_base', '_odom_frame:=tc_odom',
                                 '_backend:=rbpf', '_particles:=5',
                                 '_map_frame:=tc_map', '_map_update_interval:=0.1', '_temporalUpdate:=0.05',
                                 'scan:=%s/scan' % ns, 'map:=%s/map' % ns, 'map_metadata:=%s/map_metadata' % ns,
                                 'dynamic_map:=%s/dynamic_map' % ns],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        lines = []
        threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True).start()

        def printed(text, timeout=20.0):
            deadline = time.time() + timeout
            while time.time() < deadline:
                if any(text in l for l in lines):
                    return True
                time.sleep(0.1)
            return False

        try:
            self.assertTrue(printed('/base_link'), 'no warning about ~base_link: %s' % ''.join(lines))
            self.assertIn('did you mean base_frame?', next(l for l in lines if '/base_link' in l))
            static = tf2_ros.StaticTransformBroadcaster()
            tfs = []
            for parent, child in (('tc_odom', 'tc_base'), ('tc_base', 'tc_laser')):
                t = TransformStamped()
                t.header.frame_id, t.child_frame_id = parent, child
                t.transform.rotation.w = 1.0
                tfs.append(t)
            static.sendTransform(tfs)
            pub = rospy.Publisher(ns + '/scan', LaserScan, queue_size=10)
            rospy.sleep(1.0)

            def scan(stamp, n=90, announced=90, ranges=None):
                m = LaserScan()
                m.header.stamp, m.header.frame_id = stamp, 'tc_laser'
                m.angle_min, m.angle_increment = -math.pi / 2, math.pi / 90
                m.angle_max = m.angle_min + (announced - 1) * m.angle_increment
                m.range_min, m.range_max = 0.1, 10.0
                m.ranges = ranges if ranges is not None else [2.0 + 0.01 * (i % 7) for i in range(n)]
                return m

            now = rospy.Time.now()
            pub.publish(scan(now, n=60))  # fewer beams than angle_min..angle_max announce
            self.assertTrue(printed('announce 90 beams but it has 60'), ''.join(lines))
            rospy.sleep(6.0)  # the warning is throttled (5 s), as a flood of bad scans would be
            bad = scan(now)
            bad.angle_increment = float('nan')
            pub.publish(bad)
            self.assertTrue(printed('angle_increment'), ''.join(lines))
            rospy.sleep(6.0)
            pub.publish(scan(now, ranges=[float('nan')] * 90))
            self.assertTrue(printed('none of its 90 ranges is usable'), ''.join(lines))
            for k in range(5):  # good scans: the node builds a map from them
                pub.publish(scan(now + rospy.Duration(0.1 * (k + 1))))
                rospy.sleep(0.3)
            rospy.wait_for_message(ns + '/map', OccupancyGrid, timeout=20.0)
            # ~entropy is the particle filter's alone: the instance runs the backend it was asked for.
            entropy = rospy.wait_for_message('/typo_check/entropy', Float64, timeout=10.0)
            self.assertTrue(math.isfinite(entropy.data))
            pub.publish(scan(now - rospy.Duration(30.0)))  # a bag restarted
            self.assertTrue(printed('time went backwards'), ''.join(lines))
            self.assertIsNone(proc.poll(), 'slam_gmapping died on bad input')
        finally:
            proc.terminate()
            proc.wait()


if __name__ == '__main__':
    rospy.init_node('test_slam_home')
    rostest.rosrun('mbot_slam_navigation', 'slam_home', SlamHomeTest)
