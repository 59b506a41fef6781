"""Figures of a nav_msgs/OccupancyGrid that a person checks: known area, free and occupied cells."""
from dataclasses import dataclass

import numpy as np


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


def map_stats(msg, occupied_threshold: int = 65, free_threshold: int = 25) -> MapStats:
    """Counts cells as map_saver does: >= occupied_threshold occupied, <= free_threshold free."""
    data = np.asarray(msg.data, dtype=np.int16)
    return MapStats(width=msg.info.width, height=msg.info.height, resolution=msg.info.resolution,
                    free_cells=int(np.count_nonzero((data >= 0) & (data <= free_threshold))),
                    occupied_cells=int(np.count_nonzero(data >= occupied_threshold)),
                    unknown_cells=int(np.count_nonzero(data < 0)))
