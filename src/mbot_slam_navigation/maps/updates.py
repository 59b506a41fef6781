"""A map followed from its topic and its <topic>_updates (nav_msgs/OccupancyGrid whole, then
map_msgs/OccupancyGridUpdate windows), as slam_gmapping and map_merge send it with publish_updates.

The two topics are two connections: an update can arrive before the whole map that was sent
before it, and would be lost under it or not fit its size. The core's MapUpdateLog keeps the
updates newer than the whole map held and writes them again into each whole map that arrives.
"""
import threading
from typing import Optional

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.frontiers import Grid


def grid_of(msg) -> Grid:
    """A nav_msgs/OccupancyGrid as a Grid (rows along y)."""
    return Grid(np.asarray(msg.data, np.int8).reshape(msg.info.height, msg.info.width), msg.info.resolution,
                (msg.info.origin.position.x, msg.info.origin.position.y))


def _patched(grid: Grid, windows) -> Grid:
    """`grid` with the windows (x, y, width, height, data) written in, as a new Grid (readers may hold
    the old one); windows that do not fit it are left out."""
    data = None
    rows, cols = grid.data.shape
    for x, y, w, h, cells in windows:
        if x < 0 or y < 0 or x + w > cols or y + h > rows or len(cells) != w * h:
            continue
        if data is None:
            data = grid.data.copy()
        data[y:y + h, x:x + w] = np.asarray(cells, np.int8).reshape(h, w)
    return grid if data is None else Grid(data, grid.resolution, grid.origin)


class FollowedMap:
    """The map held (`grid`, a Grid replaced, never changed in place, or None before the first whole
    map) and its `stamp`. whole() and update() may be called from two subscribers' threads at once."""

    def __init__(self):
        self._log = _core._MapUpdateLog()
        self._lock = threading.Lock()
        self.grid: Optional[Grid] = None
        self.stamp = None

    def whole(self, msg, now) -> Grid:
        """A whole map (nav_msgs/OccupancyGrid) arrived at `now` (rospy.Time): held, with the updates
        newer than it; the map held stays when this one is stale (older than it, and the clock has
        not gone back)."""
        grid = grid_of(msg)
        with self._lock:
            newer = self._log.whole(msg.header.stamp.to_nsec(), now.to_nsec())
            if newer is not None:
                self.grid, self.stamp = _patched(grid, newer), msg.header.stamp
            return self.grid

    def update(self, msg) -> Optional[Grid]:
        """An update (map_msgs/OccupancyGridUpdate) arrived: the map held with it written in, or None
        when it is not for the map held now (none yet, older than it, or for a whole map of another
        size still on its way: then it is written into that one when it comes)."""
        with self._lock:
            if not self._log.update(msg.header.stamp.to_nsec(), msg.x, msg.y, msg.width, msg.height,
                                    np.asarray(msg.data, np.int8)):
                return None
            grid = _patched(self.grid, [(msg.x, msg.y, msg.width, msg.height, msg.data)])
            if grid is self.grid:
                return None
            self.grid, self.stamp = grid, msg.header.stamp
            return grid
