#!/usr/bin/env python3
"""The exploration tutorial as a user runs it (exploration_tutorial.test): robot_gazebo_navigation.launch
(simulator, slam_gmapping) and robot_gazebo_navigation_move.launch (amcl, move_base), headless.

1. Method 1: the real rviz with urdf/xacro/default.rviz on a virtual display; the screenshot shows
   the map, the robot where tf has it and the laser; a 2D Nav Goal click and drag sends the robot
   across the living room and the map grows.
2. Method 2: `rosrun mbot_slam_navigation random_navigation.py` with a goal limit of two rounds;
   then `map_saver -f` and the saved map against the world.
Screenshots and the saved map are kept beside the test results (artifacts/). Tests run in order.
"""
import math
import os
import re
import subprocess
import threading
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped
from move_base_msgs.msg import MoveBaseActionResult
from nav_msgs.msg import OccupancyGrid, Odometry
from tf2_msgs.msg import TFMessage

from mbot_slam_navigation.home_rooms import room_coverage
from mbot_slam_navigation.map_stats import map_stats
from mbot_slam_navigation.maps.map_io import SAVER_OCCUPIED, load_map
from mbot_slam_navigation.msg import Contact
from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, rasterize
from mbot_slam_navigation.sim.sdf_world import load_world
from rviz_screen import (RosoutFile, RvizScreen, artifact_dir, laser_pixels, map_free_pixels, render_area,
                         robot_pixels, to_pixel, wait_for)

PKG = rospkg.RosPack().get_path('mbot_slam_navigation')
CLICK_GOAL = (-3.0, -2.0)  # [m, map] a 2D Nav Goal in the living room, 3.6 m from the spawn point
GOALS = 18                 # two rounds of p1..p9
MIN_SUCCESS = 0.9
WALL_TOL = 0.1             # [m] saved walls against the world's
MIN_ROOM_COVERAGE = 0.8    # share of each room's floor the saved map marks free


class ExplorationTutorialTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = artifact_dir()
        cls.rosout = RosoutFile(os.path.join(cls.out, 'exploration_rosout.log'))
        cls.lock = threading.Lock()
        cls.truth = None
        cls.contacts, cls.clicked, cls.results = [], [], []
        rospy.Subscriber('/base_pose_ground_truth', Odometry, cls.on_truth, queue_size=10)
        rospy.Subscriber('/gazebo/contacts', Contact, cls.contacts.append)
        rospy.Subscriber('/move_base_simple/goal', PoseStamped, cls.clicked.append)
        rospy.Subscriber('/move_base/result', MoveBaseActionResult, cls.results.append)
        cls.map_odom_publishers = set()
        rospy.Subscriber('/tf', TFMessage, cls.on_tf, queue_size=100)
        cls.tf = tf2_ros.Buffer()
        cls.tf_listener = tf2_ros.TransformListener(cls.tf)
        rospy.wait_for_message('/map', OccupancyGrid, timeout=120.0)
        cls.tf.lookup_transform('map', 'base_footprint', rospy.Time(0), rospy.Duration(60.0))

    @classmethod
    def on_truth(cls, msg):
        with cls.lock:
            cls.truth = (msg.pose.pose.position.x, msg.pose.pose.position.y)

    @classmethod
    def on_tf(cls, msg):
        if any(t.header.frame_id == 'map' and t.child_frame_id == 'odom' for t in msg.transforms):
            cls.map_odom_publishers.add(msg._connection_header['callerid'])

    def robot_in_map(self):
        t = self.tf.lookup_transform('map', 'base_footprint', rospy.Time(0), rospy.Duration(5.0)).transform.translation
        return t.x, t.y

    def test_1_rviz_shows_the_stack_and_2d_nav_goal_drives_the_robot(self):
        screen = RvizScreen(os.path.join(PKG, 'urdf', 'xacro', 'default.rviz'), os.path.join(self.out, 'rviz.log'))
        try:
            shot = os.path.join(self.out, 'exploration_rviz_start.png')

            seen = {}

            def drawn():
                """True once the screenshot shows the map, the laser and the robot where tf has it."""
                if not screen.alive():
                    return True  # nothing more to wait for
                img = screen.shot(shot)
                seen['area'] = area = render_area(img)
                if area is None:
                    return False
                x, y = self.robot_in_map()
                seen.update(map=map_free_pixels(img, area), laser=laser_pixels(img, area),
                            robot=robot_pixels(img, area, x, y))
                return seen['map'] > 20000 and seen['laser'] > 50 and seen['robot'] > 80

            ok = wait_for(drawn, timeout=120.0, period=3.0)
            self.assertTrue(screen.alive(), 'rviz exited; see %s' % os.path.join(self.out, 'rviz.log'))
            self.assertTrue(ok, 'rviz does not show the map, robot and laser (pixels: %s; %s)' % (seen, shot))
            area = seen['area']
            rospy.loginfo('rviz shows map %(map)d, laser %(laser)d, robot %(robot)d pixels', seen)

            # 2D Nav Goal: the tool's key is "g"; click at the goal, drag towards +x for the heading.
            known_before = map_stats(rospy.wait_for_message('/map', OccupancyGrid, timeout=30.0)).known_area_m2
            u, v = to_pixel(area, *CLICK_GOAL)
            screen.xdotool('mousemove', (area[0] + area[2]) // 2, (area[1] + area[3]) // 2, 'click', 1, 'key', 'g',
                           'mousemove', u, v, 'mousedown', 1, 'mousemove', u + 10, v, 'mousemove', u + 30, v,
                           'mouseup', 1)
            self.assertTrue(wait_for(lambda: self.clicked, timeout=20.0, period=0.5),
                            'rviz published nothing on /move_base_simple/goal after the 2D Nav Goal click')
            g = self.clicked[0].pose
            self.assertEqual(self.clicked[0].header.frame_id, 'map')
            self.assertLess(math.hypot(g.position.x - CLICK_GOAL[0], g.position.y - CLICK_GOAL[1]), 0.1,
                            'the goal landed at (%.2f, %.2f)' % (g.position.x, g.position.y))
            self.assertLess(abs(2.0 * math.atan2(g.orientation.z, g.orientation.w)), 0.1, 'heading not +x')
            done = wait_for(lambda: self.results, timeout=300.0, period=1.0)
            self.assertTrue(done, 'move_base did not finish the clicked goal')
            self.assertEqual(done[0].status.status, 3, 'move_base: %s' % done[0].status.text)  # SUCCEEDED
            with self.lock:
                tx, ty = self.truth
            self.assertLess(math.hypot(tx - g.position.x, ty - g.position.y), 0.3)
            rospy.sleep(6.0)  # a map update after arriving (slam_gmapping publishes every 5 s)
            known_after = map_stats(rospy.wait_for_message('/map', OccupancyGrid, timeout=30.0)).known_area_m2
            rospy.loginfo('2D Nav Goal: reached (%.2f, %.2f); known map area %.1f -> %.1f m^2', tx, ty, known_before,
                          known_after)
            self.assertGreater(known_after, known_before + 2.0, 'the map did not grow')
            img = screen.shot(os.path.join(self.out, 'exploration_rviz_goal.png'))
            x, y = self.robot_in_map()
            self.assertGreater(robot_pixels(img, area, x, y), 80, 'rviz does not show the robot at its goal')
            self.assertEqual(self.contacts, [], 'the robot touched something')
        finally:
            screen.close()

    def test_2_random_navigation_two_rounds_then_map_saver(self):
        cmd = ['rosrun', 'mbot_slam_navigation', 'random_navigation.py', '_max_goals:=%d' % GOALS, '_seed:=1',
               '__name:=random_navigation']
        run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=2400)
        with open(os.path.join(self.out, 'random_navigation.log'), 'w') as f:
            f.write(run.stdout)
        self.assertEqual(run.returncode, 0, run.stdout[-3000:])
        m = re.search(r'Random navigation summary: (\d+) goals, (\d+) succeeded', run.stdout)
        self.assertIsNotNone(m, 'no summary in the log:\n' + run.stdout[-3000:])
        goals, successes = int(m.group(1)), int(m.group(2))
        rospy.loginfo('random_navigation: %d/%d goals reached', successes, goals)
        self.assertEqual(goals, GOALS)
        self.assertEqual(len(re.findall(r'Going to: p\d', run.stdout)), GOALS)
        self.assertGreaterEqual(successes, MIN_SUCCESS * goals, run.stdout[-3000:])
        self.assertEqual(len(re.findall(r'Success so far', run.stdout)), GOALS)
        self.assertNotIn('not tracking', run.stdout)  # actionlib's send_goal race
        self.assertEqual(self.contacts, [], 'the robot touched something')
        # slam_gmapping alone owns map -> odom (the tutorial also starts amcl, which would compete).
        self.assertEqual(self.map_odom_publishers, {'/slam_gmapping'})

        name = os.path.join(self.out, 'exploration_map')
        saver = subprocess.run(['rosrun', 'mbot_slam_navigation', 'map_saver', '-f', name], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, timeout=120)
        self.assertEqual(saver.returncode, 0, saver.stdout)
        saved = load_map(name + '.yaml')
        world = load_world(os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world'))
        rows, cols = np.nonzero(saved.data >= SAVER_OCCUPIED)
        walls = np.column_stack([saved.origin[0] + (cols + 0.5) * saved.resolution,
                                 saved.origin[1] + (rows + 0.5) * saved.resolution])
        d = distance_to_surfaces(world, walls)
        within = float(np.mean(d <= WALL_TOL))
        truth, origin = rasterize(world, saved.resolution)
        coverage = room_coverage(saved, truth, origin, saved.resolution)
        rospy.loginfo('saved map: %d wall cells, %.2f%% within %.2f m of the world (median %.3f m); rooms seen: %s',
                      len(d), 100 * within, WALL_TOL, np.median(d),
                      ', '.join('%s %.0f%%' % (k, 100 * v) for k, v in coverage.items()))
        self.assertGreater(len(d), 1500)
        self.assertGreaterEqual(within, 0.95)
        for room, share in coverage.items():
            self.assertGreaterEqual(share, MIN_ROOM_COVERAGE, '%s: only %.0f%% of its floor mapped' % (room, 100 * share))


if __name__ == '__main__':
    rospy.init_node('exploration_tutorial_test')
    rostest.rosrun('mbot_slam_navigation', 'exploration_tutorial', ExplorationTutorialTest)
