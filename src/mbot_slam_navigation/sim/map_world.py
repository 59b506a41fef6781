"""A map_server map (YAML + image) as a world: the saved map of a building, or a floor plan, simulated.

The map is read as map_server reads it (maps/map_io.load_map: image, resolution, origin, negate,
occupied_thresh, free_thresh, mode), and becomes one grid shape: occupied cells are walls of every
height (raw mode: values from occupied_thresh x 100 to 100); unknown cells are walls too by default
(a saved map's outside, beyond which the laser saw nothing), or free floor with map_unknown='free'.
With unknown cells solid, so is the world beyond the image: a frame of one solid cell surrounds it
(a map cropped through a room does not let the robot out into endless floor). The grid sits where
map_server puts the map: the lower-left pixel's corner at origin (x, y), turned by origin's yaw; map
frame = world frame.
"""
import math

import numpy as np

from mbot_slam_navigation.maps.map_io import MapFileError, load_map
from mbot_slam_navigation.sim.sdf_world import Shape, World

UNKNOWN_CHOICES = ('solid', 'free')


def load_map_world(yaml_path: str, map_unknown: str = 'solid') -> World:
    """The map as a World with one grid shape; raises MapFileError naming the file and key."""
    if map_unknown not in UNKNOWN_CHOICES:
        raise MapFileError(yaml_path, "unknown cells must be simulated as 'solid' or 'free', not %r" % (map_unknown,),
                           'map_unknown')
    m = load_map(yaml_path)
    if m.mode == 'raw':  # the pixel's value is the occupancy: 0..100, 255 unknown
        value = m.data.view(np.uint8)
        solid, unknown = (value >= 100 * m.occupied_thresh) & (value <= 100), value > 100
    else:  # trinary and scale: occupied cells are 100, unknown -1 (scale: between the thresholds is floor)
        solid, unknown = m.data == 100, m.data < 0
    if map_unknown == 'solid':
        solid = solid | unknown
    if not solid.any() and map_unknown == 'free':
        raise MapFileError(yaml_path, 'has no occupied cell: nothing to simulate', 'image')
    x, y, yaw = m.origin
    if map_unknown == 'solid':
        solid = np.pad(solid, 1, constant_values=True)
        r = m.resolution  # the origin moves one cell down and left, along the map's own axes
        x, y = x - r * (math.cos(yaw) - math.sin(yaw)), y - r * (math.sin(yaw) + math.cos(yaw))
    name = yaml_path.rsplit('/', 1)[-1]
    return World(name=name, shapes=[Shape('grid', x, y, yaw, cells=solid, resolution=m.resolution, name=name)])
