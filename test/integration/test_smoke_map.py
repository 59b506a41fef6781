#!/usr/bin/env python3
"""The map built from the simulated room has its walls where the room's walls are."""
import unittest

import numpy as np
import rospy
import rostest
from nav_msgs.msg import OccupancyGrid


class SmokeMapTest(unittest.TestCase):
    def test_walls_of_the_room_are_mapped(self):
        # Let a few dozen scans accumulate (the sensor is still, so the grid converges), then check.
        rospy.wait_for_message('map', OccupancyGrid, timeout=45.0)
        rospy.sleep(3.0)
        msg = rospy.wait_for_message('map', OccupancyGrid, timeout=45.0)
        self.assertIsNotNone(msg)
        self.assertEqual(msg.header.frame_id, 'map')
        grid = np.asarray(msg.data, dtype=np.int16).reshape(msg.info.height, msg.info.width)
        res, ox, oy = msg.info.resolution, msg.info.origin.position.x, msg.info.origin.position.y

        def value(x, y):
            return grid[int(np.floor((y - oy) / res)), int(np.floor((x - ox) / res))]

        def wall(x, y, dx, dy):
            # A beam ends on the wall's surface, so the hit may land in either cell that touches it.
            return max(value(x - dx, y - dy), value(x + dx, y + dy))

        # The room spans [0, 4] x [0, 3]; walls on its boundary lines. A 1-degree laser leaves gaps
        # where beams graze a far wall, so most (not all) of each wall must be marked.
        h = res / 2
        for name, points, dx, dy in (
                ('south', [(x, 0.0) for x in np.arange(0.1, 3.9, res)], 0, h),
                ('north', [(x, 3.0) for x in np.arange(0.1, 3.9, res)], 0, h),
                ('west', [(0.0, y) for y in np.arange(0.1, 2.9, res)], h, 0),
                ('east', [(4.0, y) for y in np.arange(0.1, 2.9, res)], h, 0)):
            marked = np.mean([wall(x, y, dx, dy) >= 65 for x, y in points])
            self.assertGreaterEqual(marked, 0.85, '%s wall: only %.0f%% marked' % (name, 100 * marked))
        # Nothing inside the room (away from the walls) is marked occupied.
        for x in np.arange(0.15, 3.9, res):
            for y in np.arange(0.15, 2.9, res):
                self.assertLess(value(x, y), 65, 'phantom obstacle at (%.2f, %.2f)' % (x, y))
        # Inside is free, outside unseen.
        self.assertTrue(0 <= value(1.5, 1.2) <= 25)
        self.assertTrue(0 <= value(3.5, 2.5) <= 25)
        self.assertEqual(value(-0.5, -0.5), -1)


if __name__ == '__main__':
    rospy.init_node('test_smoke_map')
    rostest.rosrun('mbot_slam_navigation', 'smoke_map', SmokeMapTest)
