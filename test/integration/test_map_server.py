#!/usr/bin/env python3
"""map_server and map_saver as a user runs them (map_server.test): the served map is the file's,
change_map refuses a bad file and keeps the map, map_saver writes back the same grid, and the
error cases end with a message and a non-zero exit."""
import os
import subprocess
import tempfile
import unittest

import numpy as np
import rospkg
import rospy
import rostest
from nav_msgs.msg import MapMetaData, OccupancyGrid
from nav_msgs.srv import GetMap, LoadMap, LoadMapResponse

from mbot_slam_navigation.maps.map_io import load_map

PKG = rospkg.RosPack().get_path('mbot_slam_navigation')
MAP = os.path.join(PKG, 'maps', 'map.yaml')


def rosrun(*args, timeout=60):
    return subprocess.run(['rosrun', 'mbot_slam_navigation'] + list(args), capture_output=True, text=True,
                          timeout=timeout)


class MapServerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp()
        rospy.wait_for_service('/static_map', timeout=30.0)

    def test_1_serves_the_file_latched_and_by_service(self):
        expected = load_map(MAP)
        msg = rospy.wait_for_message('/map', OccupancyGrid, timeout=10.0)
        meta = rospy.wait_for_message('/map_metadata', MapMetaData, timeout=10.0)
        self.assertEqual(msg.header.frame_id, 'map')
        self.assertEqual((meta.width, meta.height), (expected.data.shape[1], expected.data.shape[0]))
        self.assertAlmostEqual(meta.origin.position.x, expected.origin[0], places=5)
        np.testing.assert_array_equal(np.array(msg.data, np.int8).reshape(expected.data.shape), expected.data)
        served = rospy.ServiceProxy('/static_map', GetMap)().map
        self.assertEqual(list(served.data), list(msg.data))

    def test_2_change_map_refuses_bad_files_and_keeps_the_map(self):
        change = rospy.ServiceProxy('/change_map', LoadMap)
        self.assertEqual(change(map_url='/nonexistent/map.yaml').result, LoadMapResponse.RESULT_MAP_DOES_NOT_EXIST)
        bad = os.path.join(self.tmp, 'bad.yaml')
        with open(bad, 'w') as f:
            f.write('image: map.pgm\nresolution: -0.05\norigin: [0, 0, 0]\nnegate: 0\n'
                    'occupied_thresh: 0.65\nfree_thresh: 0.196\n')
        self.assertEqual(change(map_url=bad).result, LoadMapResponse.RESULT_INVALID_MAP_METADATA)
        self.assertEqual(len(rospy.ServiceProxy('/static_map', GetMap)().map.data), load_map(MAP).data.size)

    def test_3_map_saver_writes_back_the_same_grid(self):
        out = os.path.join(self.tmp, 'saved')
        r = rosrun('map_saver', '-f', out)
        self.assertEqual(r.returncode, 0, r.stderr + r.stdout)
        np.testing.assert_array_equal(load_map(out + '.yaml').data, load_map(MAP).data)
        with open(out + '.yaml') as f:
            self.assertIn('image: saved.pgm', f.read())

    def test_4_errors_name_what_and_exit_non_zero(self):
        r = rosrun('map_saver', '-f', os.path.join(self.tmp, 'none'), '--timeout', '2', 'map:=/no_map_here')
        self.assertNotEqual(r.returncode, 0)
        self.assertIn('/no_map_here', r.stdout + r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, 'none.pgm')))
        bad = os.path.join(self.tmp, 'missing_key.yaml')
        with open(bad, 'w') as f:
            f.write('image: map.pgm\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n')
        r = rosrun('map_server', bad, '__name:=map_server_bad', timeout=30)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn(bad, r.stdout + r.stderr)
        self.assertIn("'resolution'", r.stdout + r.stderr)


if __name__ == '__main__':
    rospy.init_node('test_map_server')
    rostest.rosrun('mbot_slam_navigation', 'map_server_and_saver', MapServerTest)
