#!/usr/bin/env python3
"""sim_never_blocks.test: a subscriber stopped with SIGSTOP must not hold the simulation still.

Before this was fixed, the simulator wrote to every subscriber's socket synchronously: 20 s after
one subscriber of /scan stopped, /clock delivered nothing at all."""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan

HERE = os.path.dirname(os.path.abspath(__file__))


class ClockRate:
    """Simulated seconds per wall second of /clock, as this test receives it."""

    def __init__(self):
        self.last = None
        rospy.Subscriber('/clock', Clock, self.on_clock, queue_size=10)

    def on_clock(self, msg):
        self.last = msg.clock.to_sec()

    def measure(self, wall_s: float) -> float:
        t0, w0 = self.last, time.monotonic()
        time.sleep(wall_s)
        t1, w1 = self.last, time.monotonic()
        return (t1 - t0) / (w1 - w0)


def read_counts(path):
    with open(path) as f:
        return json.load(f)


class SimNeverBlocksTest(unittest.TestCase):
    def test_stopped_subscriber_does_not_stop_the_clock(self):
        rospy.wait_for_message('/scan', LaserScan, timeout=60.0)  # the robot is spawned
        rate = ClockRate()
        counts_file = os.path.join(tempfile.mkdtemp(), 'counts.json')
        sub = subprocess.Popen([sys.executable, os.path.join(HERE, 'idle_subscriber.py'), counts_file])
        try:
            deadline = time.monotonic() + 30.0
            while time.monotonic() < deadline and not (os.path.isfile(counts_file) and
                                                       min(read_counts(counts_file).values()) > 0):
                time.sleep(0.5)
            self.assertGreater(min(read_counts(counts_file).values()), 0, 'the subscriber never received')
            before = rate.measure(3.0)
            rospy.loginfo('clock before the stop: %.1fx real time', before)
            self.assertGreater(before, 2.0, 'real_time_factor 0 should run faster than real time')

            os.kill(sub.pid, signal.SIGSTOP)
            time.sleep(5.0)  # long enough to fill its socket buffers at this rate
            during = rate.measure(5.0)
            rospy.loginfo('clock while the subscriber is stopped: %.1fx real time', during)
            self.assertGreater(during, 0.5 * before,
                               '/clock slowed from %.1fx to %.1fx while a subscriber was stopped' % (before, during))

            os.kill(sub.pid, signal.SIGCONT)
            time.sleep(2.0)
            c0 = read_counts(counts_file)
            time.sleep(3.0)
            c1 = read_counts(counts_file)
            for key in c0:
                self.assertGreater(c1[key], c0[key], 'the subscriber receives no %s after it continued' % key)
            after = rate.measure(3.0)
            self.assertGreater(after, 0.5 * before)
        finally:
            os.kill(sub.pid, signal.SIGCONT)
            sub.terminate()
            sub.wait(timeout=10.0)


if __name__ == '__main__':
    rospy.init_node('test_sim_never_blocks')
    rostest.rosrun('mbot_slam_navigation', 'sim_never_blocks', SimNeverBlocksTest)
