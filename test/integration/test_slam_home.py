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
import tf2_ros
from geometry_msgs.msg import Twist
from nav_msgs.msg import OccupancyGrid, Odometry

from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, occupied_points
from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.sim.transforms import quaternion_to_yaw

# Around the living room twice (world frame, m): clear of the sofa, coffee table and plant.
ROUTE = [(-1.0, -1.0), (-2.0, -2.8), (-4.2, -3.2), (-4.6, -1.5), (-3.0, -0.3), (0.0, -0.3), (0.3, -2.5),
         (-1.0, -3.2), (-2.0, -2.8), (-4.2, -3.2), (-4.6, -1.5), (-3.0, -0.3), (0.0, -0.5)]


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
        for wx, wy in ROUTE:
            deadline = rospy.Time.now() + rospy.Duration(60.0)
            while not rospy.is_shutdown():
                self.assertLess(rospy.Time.now(), deadline, 'route point (%.1f, %.1f) not reached' % (wx, wy))
                p, stamp = truth.get('pose'), truth.get('stamp')
                if p is None:
                    rate.sleep()
                    continue
                x, y = p.position.x, p.position.y
                yaw = quaternion_to_yaw(p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w)
                dist, bearing = math.hypot(wx - x, wy - y), math.atan2(wy - y, wx - x)
                if dist < 0.15:
                    break
                err = math.atan2(math.sin(bearing - yaw), math.cos(bearing - yaw))
                t = Twist()
                t.angular.z = max(-0.8, min(0.8, 2.0 * err))
                t.linear.x = 0.3 if abs(err) < 0.4 else 0.0
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

    def test_tutorial_typo_gets_a_warning(self):
        # The tutorial sets ~base_link (a typo for ~base_frame). Start a second, idle instance as the
        # tutorial would (no scans, no tf) and read what it prints in the terminal.
        proc = subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'slam_gmapping', '__name:=typo_check',
                                 '_base_link:=base_footprint', '_transform_publish_period:=0', 'scan:=/typo_check/scan',
                                 'map:=/typo_check/map', 'map_metadata:=/typo_check/map_metadata',
                                 'dynamic_map:=/typo_check/dynamic_map'],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        lines = []
        reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
        reader.start()
        deadline = time.time() + 30.0
        while time.time() < deadline and not any('~base_link' in l for l in lines):
            time.sleep(0.2)
        proc.terminate()
        proc.wait()
        hits = [l for l in lines if '~base_link' in l]
        self.assertTrue(hits, 'no warning about ~base_link; output: %s' % ''.join(lines))
        self.assertIn('did you mean ~base_frame', hits[0])


if __name__ == '__main__':
    rospy.init_node('test_slam_home')
    rostest.rosrun('mbot_slam_navigation', 'slam_home', SlamHomeTest)
