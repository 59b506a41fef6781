"""The simulated home's rooms (worlds/mbot_sim_gazebo_navigation.world, the table in DESIGN.md) and
how much of each a saved map has seen. World frame = the map frame of a SLAM run started at the
spawn point (0, 0, 0); metres."""
import os
from dataclasses import dataclass
from typing import Dict, Sequence, Tuple

import yaml

import numpy as np

from mbot_slam_navigation.map_stats import free_at
from mbot_slam_navigation.maps.map_io import SAVER_FREE, LoadedMap


@dataclass(frozen=True)
class Room:
    name: str
    xmin: float
    xmax: float
    ymin: float
    ymax: float


HOME_ROOMS = (
    Room('living room', -5.4, 1.2, -6.0, 0.9),
    Room('kitchen', 1.2, 4.5, -6.0, -3.6),
    Room('dining room', 1.2, 4.5, -3.6, -1.2),
    Room('bathroom', 1.2, 4.5, -1.2, 0.9),
    Room('second bedroom', 0.2, 4.5, 0.9, 3.6),
    Room('study', -2.0, 0.2, 0.9, 3.6),
    Room('master bedroom', -5.4, -2.0, 0.9, 3.6),
    Room('balcony', -7.5, -5.4, -4.2, 0.0),
)


def rooms_file_of(world_path: str) -> str:
    """worlds/<name>.world -> worlds/<name>.rooms.yaml (tools/generate_world.py writes both)."""
    return os.path.splitext(world_path)[0] + '.rooms.yaml'


def load_rooms(path: str) -> Tuple[Room, ...]:
    """The rooms of a rooms file; ValueError naming the file and the entry that is wrong."""
    with open(path) as f:
        data = yaml.safe_load(f) or {}
    rooms = []
    for i, r in enumerate(data.get('rooms') or []):
        try:
            room = Room(str(r['name']), float(r['xmin']), float(r['xmax']), float(r['ymin']), float(r['ymax']))
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError('%s: rooms[%d]: needs name, xmin, xmax, ymin, ymax (%s)' % (path, i, e)) from None
        if not (room.xmin < room.xmax and room.ymin < room.ymax):
            raise ValueError('%s: rooms[%d] "%s": xmin < xmax and ymin < ymax required' % (path, i, room.name))
        rooms.append(room)
    return tuple(rooms)


def room_coverage(m: LoadedMap, truth: np.ndarray, truth_origin, truth_resolution: float,
                  margin: float = 0.15, rooms: Sequence[Room] = HOME_ROOMS) -> Dict[str, float]:
    """For each room, the share of its truly free floor (cells of `truth`, the world rasterized at
    `truth_resolution` with origin `truth_origin`, 0 = free, more than `margin` from its walls) that
    the map `m` marks free. A floor point the map does not cover counts as unseen."""
    h, w = truth.shape
    xs = truth_origin[0] + (np.arange(w) + 0.5) * truth_resolution
    ys = truth_origin[1] + (np.arange(h) + 0.5) * truth_resolution
    gx, gy = np.meshgrid(xs, ys)
    seen_free = free_at(m.data, m.resolution, m.origin, gx, gy, SAVER_FREE)
    out = {}
    for r in rooms:
        floor = ((truth == 0) & (gx > r.xmin + margin) & (gx < r.xmax - margin)
                 & (gy > r.ymin + margin) & (gy < r.ymax - margin))
        out[r.name] = float(seen_free[floor].mean()) if floor.any() else 0.0
    return out
