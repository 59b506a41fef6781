#!/usr/bin/env python3
"""With real_time_factor 0 the simulated clock advances faster than the wall clock."""
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan


class SimClockTest(unittest.TestCase):
    def test_clock_runs_faster_than_wall_time(self):
        rospy.wait_for_message('/scan', LaserScan, timeout=60.0)  # the robot is spawned
        t0 = rospy.wait_for_message('/clock', Clock, timeout=10.0).clock.to_sec()
        w0 = time.monotonic()
        time.sleep(3.0)
        t1 = rospy.wait_for_message('/clock', Clock, timeout=10.0).clock.to_sec()
        w1 = time.monotonic()
        # Generous: the benchmark measures the real factor; here only "faster than real time".
        self.assertGreater(t1 - t0, 2.0 * (w1 - w0), 'sim advanced %.1f s in %.1f s wall' % (t1 - t0, w1 - w0))


if __name__ == '__main__':
    rospy.init_node('test_sim_clock')
    rostest.rosrun('mbot_slam_navigation', 'sim_clock', SimClockTest)
