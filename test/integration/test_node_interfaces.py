#!/usr/bin/env python3
"""rostest: the running nodes offer what their reference pages declare (node_interfaces.py).

args: PAGE:NODE ... (e.g. slam_gmapping:/slam_gmapping gazebo_sim:/gazebo). Waits up to 60 s of
wall time for the differences to go (nodes advertise as they start); then fails listing them."""
import sys
import time
import unittest

import rospy
import rostest

from node_interfaces import mismatches

PAIRS = [a.split(':', 1) for a in rospy.myargv(sys.argv)[1:] if ':' in a and not a.startswith('--')]


class NodeInterfacesTest(unittest.TestCase):
    def test_the_nodes_offer_what_their_pages_declare(self):
        self.assertTrue(PAIRS, 'no PAGE:NODE arguments')
        deadline = time.monotonic() + 60.0
        while True:
            problems = [p for page, node in PAIRS for p in mismatches(page, node)]
            if not problems or time.monotonic() > deadline:
                break
            time.sleep(1.0)
        self.assertEqual(problems, [], '\n' + '\n'.join(problems))


if __name__ == '__main__':
    rospy.init_node('node_interfaces_test')
    rostest.rosrun('mbot_slam_navigation', 'node_interfaces', NodeInterfacesTest)
