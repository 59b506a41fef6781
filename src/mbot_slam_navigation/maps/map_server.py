"""map_server and map_saver, as ROS's map_server package offers them.

map_server MAP.yaml: latched `map` and `map_metadata`, the `static_map` service (nav_msgs/GetMap)
and `change_map` (nav_msgs/LoadMap); `~frame_id` (default "map"). A map that cannot be loaded at
start is an error naming the file and key, and a non-zero exit; one asked for through change_map is
refused with the reason and the current map is kept.

map_saver [-f NAME] [--occ N] [--free N] [--timeout S]: saves the first map received on `map`
(remappable with map:=TOPIC, or the private parameter _map:=TOPIC) as NAME.pgm and NAME.yaml.
"""
import argparse
import time
import os
import sys

import numpy as np
import rospy
from nav_msgs.msg import MapMetaData, OccupancyGrid
from nav_msgs.srv import GetMap, GetMapResponse, LoadMap, LoadMapResponse

from mbot_slam_navigation.maps.map_io import SAVER_FREE, SAVER_OCCUPIED, MapFileError, load_map, save_map
from mbot_slam_navigation.nav.params import ParamReader
from mbot_slam_navigation.ros_msgs import occupancy_grid_msg, pose_from_msg


def read_parameters(r: ParamReader) -> dict:
    """map_server's parameter."""
    return {'frame_id': r.frame('frame_id', 'map', "the map's frame")}


def read_saver_parameters(r: ParamReader) -> dict:
    """map_saver's parameter (its thresholds and name are arguments)."""
    return {'map': r.string('map', 'map', 'the map topic to save (or remap map:=TOPIC)')}


class MapServer:
    def __init__(self, yaml_path: str):
        r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
        self.frame_id = read_parameters(r)['frame_id']
        r.report_unknown()
        self.map_pub = rospy.Publisher('map', OccupancyGrid, queue_size=1, latch=True)
        self.meta_pub = rospy.Publisher('map_metadata', MapMetaData, queue_size=1, latch=True)
        self.msg = None
        self._publish(load_map(yaml_path), yaml_path)  # MapFileError ends the node: nothing to serve
        rospy.Service('static_map', GetMap, lambda _req: GetMapResponse(map=self.msg))
        rospy.Service('change_map', LoadMap, self._change_map)

    def _publish(self, loaded, path):
        self.msg = occupancy_grid_msg(loaded.data, loaded.resolution, loaded.origin, self.frame_id, rospy.Time.now())
        self.meta_pub.publish(self.msg.info)
        self.map_pub.publish(self.msg)
        rospy.loginfo('map_server: read a %d x %d map @ %.3f m/cell from %s', self.msg.info.width,
                      self.msg.info.height, self.msg.info.resolution, path)

    def _change_map(self, req):
        if not os.path.exists(req.map_url):
            rospy.logerr('map_server: change_map: %s does not exist; keeping the current map', req.map_url)
            return LoadMapResponse(result=LoadMapResponse.RESULT_MAP_DOES_NOT_EXIST)
        try:
            loaded = load_map(req.map_url)
        except MapFileError as e:
            rospy.logerr('map_server: change_map: %s; keeping the current map', e)
            image_fault = e.key == 'image'
            return LoadMapResponse(result=LoadMapResponse.RESULT_INVALID_MAP_DATA if image_fault
                                   else LoadMapResponse.RESULT_INVALID_MAP_METADATA)
        self._publish(loaded, req.map_url)
        return LoadMapResponse(map=self.msg, result=LoadMapResponse.RESULT_SUCCESS)


def map_server_main(argv=None):
    rospy.init_node('map_server')
    args = rospy.myargv(argv if argv is not None else sys.argv)[1:]
    if len(args) == 2:
        rospy.logerr('map_server: the "map_server IMAGE RESOLUTION" form is not supported; write a YAML file '
                     '(image, resolution, origin, negate, occupied_thresh, free_thresh) and pass it')
        sys.exit(1)
    if len(args) != 1:
        rospy.logerr('usage: map_server MAP.yaml')
        sys.exit(1)
    try:
        MapServer(args[0])
    except MapFileError as e:
        rospy.logerr('map_server: %s', e)
        sys.exit(1)
    rospy.spin()


def write_map(msg: OccupancyGrid, basename: str, occupied: int, free: int) -> None:
    """map_saver's output for `msg`: thresholds are occupancy values 0..100."""
    info = msg.info
    data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
    save_map(basename, data, info.resolution, pose_from_msg(info.origin),
             occupied_thresh=occupied / 100.0, free_thresh=free / 100.0)


def saver_argument_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='map_saver', description='Saves the map published on "map" as NAME.pgm and NAME.yaml '
                                      '(map:=TOPIC or _map:=TOPIC reads another topic).')
    parser.add_argument('-f', dest='name', default='map', help='output name without extension (default: map)')
    parser.add_argument('--occ', type=int, default=SAVER_OCCUPIED, help='occupied threshold, 0..100 (default %(default)s)')
    parser.add_argument('--free', type=int, default=SAVER_FREE, help='free threshold, 0..100 (default %(default)s)')
    parser.add_argument('--timeout', type=float, default=30.0,
                        help='seconds (wall clock) to wait for a map before giving up (default 30)')
    return parser


def map_saver_main(argv=None):
    parser = saver_argument_parser()
    args = parser.parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    if not (0 <= args.free < args.occ <= 100):
        parser.error('thresholds must satisfy 0 <= --free (%d) < --occ (%d) <= 100' % (args.free, args.occ))
    directory = os.path.dirname(os.path.abspath(args.name))
    if not os.path.isdir(directory):
        parser.error('-f %s: folder %s does not exist' % (args.name, directory))
    rospy.init_node('map_saver', anonymous=True)
    r = ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)
    topic = read_saver_parameters(r)['map']
    r.report_unknown()
    received = []
    sub = rospy.Subscriber(topic, OccupancyGrid, received.append, queue_size=1)
    rospy.loginfo('map_saver: waiting up to %.0f s for a map on %s', args.timeout, sub.resolved_name)
    end = time.monotonic() + args.timeout
    while not received and not rospy.is_shutdown() and time.monotonic() < end:
        time.sleep(0.05)
    if not received:
        rospy.logerr('map_saver: no map on %s within %.0f s; is SLAM or map_server running, and is the topic '
                     'right (map:=TOPIC)?', sub.resolved_name, args.timeout)
        sys.exit(1)
    msg = received[0]
    sub.unregister()
    if msg.info.width * msg.info.height != len(msg.data) or msg.info.resolution <= 0:
        rospy.logerr('map_saver: the map on %s is malformed (%d x %d cells but %d values, resolution %g)',
                     sub.resolved_name, msg.info.width, msg.info.height, len(msg.data), msg.info.resolution)
        sys.exit(1)
    rospy.loginfo('map_saver: received a %d x %d map @ %.3f m/pix', msg.info.width, msg.info.height,
                  msg.info.resolution)
    write_map(msg, args.name, args.occ, args.free)
    rospy.loginfo('map_saver: wrote %s.pgm and %s.yaml', args.name, args.name)
