#!/usr/bin/env python3
"""A subscriber to what the simulator publishes (/clock, /scan, /odom, /tf) that the test stops
with SIGSTOP: it counts what it receives and writes the counts to the file named by argv[1] once
per wall second, so the test can tell that it receives again after SIGCONT."""
import json
import os
import sys
import threading
import time

import rospy
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage


def main():
    out = sys.argv[1]
    rospy.init_node('idle_subscriber', anonymous=True, disable_signals=True)
    counts = {'clock': 0, 'scan': 0, 'odom': 0, 'tf': 0}
    lock = threading.Lock()

    def count(key):
        def cb(_msg):
            with lock:
                counts[key] += 1
        return cb

    # Large receive buffers on purpose: what the simulator must not wait for is a reader that
    # stops reading, whatever its buffers.
    rospy.Subscriber('/clock', Clock, count('clock'), queue_size=1)
    rospy.Subscriber('/scan', LaserScan, count('scan'), queue_size=1)
    rospy.Subscriber('/odom', Odometry, count('odom'), queue_size=1)
    rospy.Subscriber('/tf', TFMessage, count('tf'), queue_size=1)
    deadline = time.monotonic() + 300.0  # never outlives a test that forgot it
    while time.monotonic() < deadline:
        with lock:
            data = json.dumps(counts)
        with open(out + '.tmp', 'w') as f:
            f.write(data)
        os.replace(out + '.tmp', out)
        time.sleep(1.0)


if __name__ == '__main__':
    main()
