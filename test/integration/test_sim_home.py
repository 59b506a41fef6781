#!/usr/bin/env python3
"""The simulator as a user sees it: driving, odometry, laser ranges, collisions, services."""
import math
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan

from mbot_slam_navigation.msg import Contact, ModelState
from mbot_slam_navigation.transforms import quaternion_to_yaw, yaw_to_quaternion
from mbot_slam_navigation.srv import GetModelState, SetModelState, SpawnModel, SpawnModelRequest


def yaw_of(pose):
    q = pose.orientation
    return quaternion_to_yaw(q.x, q.y, q.z, q.w)


class SimHomeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.wait_for_message('/scan', LaserScan, timeout=60.0)
        cls.cmd = rospy.Publisher('/cmd_vel', Twist, queue_size=5)
        cls.set_state = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState)
        cls.get_state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)
        cls.contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, cls.contacts.append)

    def teleport(self, x, y, yaw):
        st = ModelState(model_name='robot')
        st.pose.position.x, st.pose.position.y = x, y
        (st.pose.orientation.x, st.pose.orientation.y, st.pose.orientation.z,
         st.pose.orientation.w) = yaw_to_quaternion(yaw)
        self.assertTrue(self.set_state(st).success)
        rospy.sleep(0.3)

    def drive(self, v, w, seconds):
        end = rospy.Time.now() + rospy.Duration(seconds)
        rate = rospy.Rate(20)
        while rospy.Time.now() < end:
            t = Twist()
            t.linear.x, t.angular.z = v, w
            self.cmd.publish(t)
            rate.sleep()

    def fresh_scan(self):
        after = rospy.Time.now()
        while True:
            scan = rospy.wait_for_message('/scan', LaserScan, timeout=10.0)
            if scan.header.stamp > after:
                return scan

    def test_1_drives_one_metre_and_stops_and_odometry_agrees(self):
        self.teleport(-3.0, -2.0, 0.0)
        odom0 = rospy.wait_for_message('/odom', Odometry, timeout=5.0).pose.pose
        self.drive(0.25, 0.0, 4.0)  # 1 m at 0.25 m/s (the acceleration ramps up and down cancel out)
        self.cmd.publish(Twist())   # stop
        rospy.sleep(1.5)
        truth = rospy.wait_for_message('/base_pose_ground_truth', Odometry, timeout=5.0)
        odom = rospy.wait_for_message('/odom', Odometry, timeout=5.0)
        travelled = truth.pose.pose.position.x + 3.0
        self.assertAlmostEqual(travelled, 1.0, delta=0.08)
        self.assertAlmostEqual(truth.pose.pose.position.y, -2.0, delta=0.02)
        self.assertEqual(truth.twist.twist.linear.x, 0.0)
        odom_travelled = math.hypot(odom.pose.pose.position.x - odom0.position.x,
                                    odom.pose.pose.position.y - odom0.position.y)
        # Slip noise of 2 % per wheel: odometry within a few centimetres over a metre, not exact.
        self.assertAlmostEqual(odom_travelled, travelled, delta=0.05)

    def test_2_scan_ranges_match_the_walls(self):
        # (pose, [(world bearing, expected range)]) from the home's plan: wall faces are 0.05 m off
        # the wall centre lines, furniture from its centre and size.
        cases = [((-1.8, -1.0, 0.0), [(math.pi / 2, 1.85), (math.pi, 3.55), (-math.pi / 2, 4.0)]),
                 ((3.0, -5.0, 0.3), [(0.0, 0.85), (-math.pi / 2, 0.95)]),
                 ((-3.0, 2.0, math.pi / 2), [(math.pi / 2, 0.35), (0.0, 0.95)])]
        for (x, y, yaw), beams in cases:
            self.teleport(x, y, yaw)
            scan = self.fresh_scan()
            for bearing, expected in beams:
                i = int(round((bearing - yaw - scan.angle_min) / scan.angle_increment)) % len(scan.ranges)
                self.assertAlmostEqual(scan.ranges[i], expected, delta=0.05,
                                       msg='pose (%.1f, %.1f, %.2f) bearing %.2f' % (x, y, yaw, bearing))

    def test_3_collision_stops_the_robot_and_is_reported(self):
        self.teleport(-2.0, -1.0, math.pi / 2)
        del self.contacts[:]
        self.drive(0.4, 0.0, 6.0)
        state = self.get_state(model_name='robot', relative_entity_name='')
        self.assertTrue(state.success)
        # The body (radius ~0.2 m) stops at the wall's south face, y = 0.85.
        self.assertLessEqual(state.pose.position.y + 0.2, 0.85 + 0.01)
        self.assertGreater(state.pose.position.y + 0.2, 0.8)
        self.assertEqual(len(self.contacts), 1)
        self.assertEqual(self.contacts[0].model_name, 'robot')

    def test_3b_cmd_vel_timeout_stops_the_robot(self):
        self.teleport(-3.0, -3.0, 0.0)
        self.drive(0.3, 0.0, 1.0)  # then silence: no stop command
        rospy.sleep(2.0)
        first = self.get_state(model_name='robot').pose.position.x
        rospy.sleep(1.0)
        self.assertAlmostEqual(self.get_state(model_name='robot').pose.position.x, first, delta=1e-6)

    def test_4_second_robot_in_a_namespace_and_bad_requests(self):
        spawn = rospy.ServiceProxy('/gazebo/spawn_urdf_model', SpawnModel)
        req = SpawnModelRequest(model_name='robot2', model_xml=rospy.get_param('/robot_description'),
                                robot_namespace='robot2')
        req.initial_pose.position.x, req.initial_pose.position.y, req.initial_pose.orientation.w = -4.0, -5.0, 1.0
        self.assertTrue(spawn(req).success)
        odom = rospy.wait_for_message('/robot2/odom', Odometry, timeout=10.0)
        self.assertEqual(odom.header.frame_id, 'robot2/odom')
        self.assertEqual(odom.child_frame_id, 'robot2/base_footprint')
        again = spawn(req)
        self.assertFalse(again.success)
        self.assertIn('exists already', again.status_message)
        self.assertIn('no model named "ghost"', self.get_state(model_name='ghost').status_message)
        bad = SpawnModelRequest(model_name='nodrive', model_xml='<robot name="x"><link name="a"/></robot>')
        res = spawn(bad)
        self.assertFalse(res.success)
        self.assertIn('no drive plugin', res.status_message)
        # The simulator still serves the first robot.
        self.assertTrue(self.get_state(model_name='robot').success)

    def test_4b_a_person_spawned_at_run_time_is_seen_touched_and_deleted(self):
        from mbot_slam_navigation.srv import DeleteModel
        spawn = rospy.ServiceProxy('/gazebo/spawn_sdf_model', SpawnModel)
        self.teleport(-3.5, -2.0, 0.0)
        req = SpawnModelRequest(model_name='visitor', model_xml='<sdf version="1.6"><actor name="a"/></sdf>')
        req.initial_pose.position.x, req.initial_pose.position.y, req.initial_pose.orientation.w = -2.0, -2.0, 1.0
        res = spawn(req)
        self.assertTrue(res.success, res.status_message)
        ahead = lambda scan: scan.ranges[int(round(-scan.angle_min / scan.angle_increment))]  # noqa: E731
        # The laser sits over the base (robot.xacro): the person's near side is 1.5 - 0.25 m away.
        self.assertAlmostEqual(ahead(self.fresh_scan()), 1.25, delta=0.05)
        state = self.get_state(model_name='visitor')
        self.assertTrue(state.success)
        self.assertAlmostEqual(state.pose.position.x, -2.0, delta=1e-6)
        del self.contacts[:]
        self.drive(0.3, 0.0, 6.0)  # straight into the person
        self.assertEqual([(c.other, c.other_kind, c.robot_at_fault) for c in self.contacts],
                         [('visitor', 'person', True)])
        bad = spawn(SpawnModelRequest(model_name='box', model_xml='<sdf version="1.6"><model name="b"/></sdf>'))
        self.assertFalse(bad.success)
        self.assertIn('no <actor>', bad.status_message)
        self.assertTrue(rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)(model_name='visitor').success)
        self.assertGreater(ahead(self.fresh_scan()), 1.5)
        # gazebo_ros's way from a shell: spawn_model -sdf -file F -model NAME -x -y
        import subprocess
        self.drive(0.0, 0.0, 0.5)  # the last command (into the person) still holds until cmd_vel_timeout
        self.teleport(-3.5, -2.0, 0.0)
        import tempfile
        with tempfile.NamedTemporaryFile('w', suffix='.sdf') as f:
            f.write('<sdf version="1.6"><actor name="a"/></sdf>')
            f.flush()
            done = subprocess.run(['rosrun', 'mbot_slam_navigation', 'spawn_model', '-sdf', '-file', f.name, '-model',
                                   'walker', '-x', '-2.0', '-y', '-2.0'], capture_output=True, text=True, timeout=60)
        self.assertEqual(done.returncode, 0, done.stdout + done.stderr)
        walker = self.get_state(model_name='walker')
        self.assertTrue(walker.success, walker.status_message)
        robot = self.get_state(model_name='robot')
        self.assertAlmostEqual(ahead(self.fresh_scan()), 1.25, delta=0.05,
                               msg='walker at (%.2f, %.2f), robot at (%.2f, %.2f)' % (
                                   walker.pose.position.x, walker.pose.position.y, robot.pose.position.x,
                                   robot.pose.position.y))
        self.assertTrue(rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)(model_name='walker').success)

    def test_5_pause_stops_the_clock_and_unpause_resumes(self):
        from rosgraph_msgs.msg import Clock
        from std_srvs.srv import Empty
        rospy.ServiceProxy('/gazebo/pause_physics', Empty)()
        time.sleep(0.5)  # let a /clock already on its way arrive
        t0 = rospy.get_rostime()
        time.sleep(1.5)  # wall time: simulated time must not move while paused
        self.assertEqual(rospy.get_rostime(), t0)
        rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()
        rospy.wait_for_message('/clock', Clock, timeout=5.0)
        self.assertGreater(rospy.get_rostime(), t0)


if __name__ == '__main__':
    rospy.init_node('test_sim_home')
    rostest.rosrun('mbot_slam_navigation', 'sim_home', SimHomeTest)
