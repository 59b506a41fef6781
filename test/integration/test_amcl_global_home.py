#!/usr/bin/env python3
"""amcl as a user meets it in the home world (amcl_global_home.test): global localization
converges while the robot drives, and a second publisher of map -> odom is reported loudly."""
import math
import threading
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Log
from std_srvs.srv import Empty

from mbot_slam_navigation.route_driver import HOME_TOUR, RouteDriver
from mbot_slam_navigation.ros_msgs import pose_from_msg

CONVERGED = 0.2  # [m]


class AmclGlobalHomeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.lock = threading.Lock()
        cls.truth = None
        cls.distance = 0.0
        cls.estimates = []  # (time, estimate, truth, distance driven)
        cls.errors_logged = []
        rospy.Subscriber('/base_pose_ground_truth', Odometry, cls.on_truth, queue_size=10)
        rospy.Subscriber('/amcl_pose', PoseWithCovarianceStamped, cls.on_estimate, queue_size=10)
        rospy.Subscriber('/rosout', Log, lambda m: cls.errors_logged.append(m.msg) if m.level >= Log.ERROR else None)
        cls.cmd = rospy.Publisher('/cmd_vel', Twist, queue_size=1)
        rospy.wait_for_message('/amcl_pose', PoseWithCovarianceStamped, timeout=60.0)

    @classmethod
    def on_truth(cls, msg):
        with cls.lock:
            p = pose_from_msg(msg.pose.pose)
            if cls.truth is not None:
                cls.distance += math.hypot(p[0] - cls.truth[0], p[1] - cls.truth[1])
            cls.truth = p

    @classmethod
    def on_estimate(cls, msg):
        with cls.lock:
            if cls.truth is not None:
                cls.estimates.append((msg.header.stamp.to_sec(), pose_from_msg(msg.pose.pose), cls.truth, cls.distance))

    def test_1_global_localization_converges_while_driving(self):
        rospy.wait_for_service('/global_localization', timeout=30.0)
        rospy.ServiceProxy('/global_localization', Empty)()
        t0, d0 = rospy.get_time(), self.distance
        driver = RouteDriver(HOME_TOUR)
        rate = rospy.Rate(20)
        while not driver.done and not rospy.is_shutdown() and rospy.get_time() - t0 < 300.0:
            with self.lock:
                truth = self.truth
            c = driver.command(truth)
            if c is None:
                break
            twist = Twist()
            twist.linear.x, twist.angular.z = c
            self.cmd.publish(twist)
            rate.sleep()
        self.cmd.publish(Twist())
        self.assertTrue(driver.done, 'the tour was not finished in 300 s')
        with self.lock:
            run = [e for e in self.estimates if e[0] > t0]
        self.assertGreater(len(run), 30)
        first_error = math.hypot(run[0][1][0] - run[0][2][0], run[0][1][1] - run[0][2][1])
        # Converged: from some estimate on, every estimate is within 0.2 m of the truth.
        converged = None
        for i, (t, est, truth, dist) in enumerate(run):
            if math.hypot(est[0] - truth[0], est[1] - truth[1]) <= CONVERGED:
                if converged is None:
                    converged = (t - t0, dist - d0, i)
            else:
                converged = None
        self.assertIsNotNone(converged, 'never settled within %.1f m; last %s' % (CONVERGED, run[-3:]))
        rospy.loginfo('global localization: first error %.2f m; within %.1f m for good after %.1f s and %.1f m of '
                      '%.1f m driven', first_error, CONVERGED, converged[0], converged[1], self.distance - d0)
        self.assertGreater(len(run) - converged[2], 20, 'converged only at the very end')

    def test_2_a_second_map_to_odom_publisher_is_reported(self):
        broadcaster = tf2_ros.TransformBroadcaster()
        for _ in range(10):
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id, t.child_frame_id = 'map', 'odom'
            t.transform.rotation.w = 1.0
            broadcaster.sendTransform(t)
            rospy.sleep(0.2)
        deadline = rospy.get_time() + 10.0
        while rospy.get_time() < deadline and not any('also publishes map -> odom' in m for m in self.errors_logged):
            rospy.sleep(0.2)
        self.assertTrue(any(rospy.get_name() in m and 'also publishes map -> odom' in m for m in self.errors_logged),
                        self.errors_logged[-3:])


if __name__ == '__main__':
    rospy.init_node('test_amcl_global_home')
    rostest.rosrun('mbot_slam_navigation', 'amcl_global_home', AmclGlobalHomeTest)
