#!/usr/bin/env python3
"""Remakes maps/map.yaml + maps/map.pgm: the car maps worlds/wall.world with this package's
slam_gmapping while move_base drives it through all three rooms, then map_saver saves the map.

Run from a sourced workspace: /usr/bin/python3 tools/make_wall_map.py [OUT_BASENAME]
"""
import os
import subprocess
import sys
import time

import rospy
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

from mbot_slam_navigation.nav.action_client import SimpleActionClient

HERE = os.path.dirname(os.path.abspath(__file__))
# wall.world (map = world frame, the car starts at the origin): the middle room, the left room
# through the top passage, back, then the right room through the bottom passage, and home.
ROUTE = [(0.0, 3.4), (-3.2, 3.6), (-3.2, -3.6), (-3.2, 3.6), (0.0, 3.4), (0.0, -3.6), (2.6, -4.2),
         (3.6, -1.0), (3.4, 3.6), (3.6, -1.0), (2.6, -4.2), (0.0, -3.6), (0.0, 0.0)]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, '..', 'maps', 'map')
    launch = subprocess.Popen(['roslaunch', 'mbot_slam_navigation', 'myrobot_slam.launch', 'gui:=false',
                               'rviz:=false', 'real_time_factor:=3.0'], stdout=subprocess.DEVNULL)
    try:
        time.sleep(5.0)
        rospy.init_node('make_wall_map')
        client = SimpleActionClient('move_base', MoveBaseAction)
        if not client.wait_for_server(rospy.Duration(60.0)):
            raise SystemExit('move_base did not come up')
        for i, (x, y) in enumerate(ROUTE):
            goal = MoveBaseGoal()
            goal.target_pose.header.frame_id = 'map'
            goal.target_pose.header.stamp = rospy.Time.now()
            goal.target_pose.pose.position.x, goal.target_pose.pose.position.y = x, y
            goal.target_pose.pose.orientation.w = 1.0
            client.send_goal(goal)
            client.wait_for_result(rospy.Duration(240.0))
            print('goal %d/%d (%.1f, %.1f): %s' % (i + 1, len(ROUTE), x, y, client.get_goal_status_text()
                                                   or client.get_state()), flush=True)
        rospy.sleep(4.0)  # one more map update
        subprocess.check_call(['rosrun', 'mbot_slam_navigation', 'map_saver', '-f', out])
    finally:
        launch.terminate()
        launch.wait()


if __name__ == '__main__':
    main()
