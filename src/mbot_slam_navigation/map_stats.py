"""Figures of a nav_msgs/OccupancyGrid that a person checks: known area, free and occupied cells."""
from dataclasses import dataclass

import numpy as np

from mbot_slam_navigation.maps.map_io import SAVER_FREE, SAVER_OCCUPIED


@dataclass
class MapStats:
    width: int
    height: int
    resolution: float      # [m]
    free_cells: int
    occupied_cells: int
    unknown_cells: int

    @property
    def known_area_m2(self) -> float:
        return (self.free_cells + self.occupied_cells) * self.resolution ** 2


def map_stats(msg, occupied_threshold: int = SAVER_OCCUPIED, free_threshold: int = SAVER_FREE) -> MapStats:
    """Counts cells as map_saver does: >= occupied_threshold occupied, <= free_threshold free."""
    data = np.asarray(msg.data, dtype=np.int16)
    return MapStats(width=msg.info.width, height=msg.info.height, resolution=msg.info.resolution,
                    free_cells=int(np.count_nonzero((data >= 0) & (data <= free_threshold))),
                    occupied_cells=int(np.count_nonzero(data >= occupied_threshold)),
                    unknown_cells=int(np.count_nonzero(data < 0)))


def free_at(data: np.ndarray, resolution: float, origin, x, y, free_threshold: int = 25) -> np.ndarray:
    """Whether an occupancy grid (rows from the lowest y; `origin` = world corner [m] of cell (0, 0))
    marks each world point (x, y) [m] free (0..free_threshold); points off the grid are not."""
    rows = np.floor((np.asarray(y) - origin[1]) / resolution).astype(int)
    cols = np.floor((np.asarray(x) - origin[0]) / resolution).astype(int)
    inside = (rows >= 0) & (cols >= 0) & (rows < data.shape[0]) & (cols < data.shape[1])
    out = np.zeros(rows.shape, bool)
    v = data[rows[inside], cols[inside]].astype(np.int16)
    out[inside] = (v >= 0) & (v <= free_threshold)
    return out
