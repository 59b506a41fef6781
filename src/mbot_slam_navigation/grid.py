"""Typed wrapper over the C++ log-odds occupancy grid and grid ray casting.

Frames and units: a grid lives in one frame (``map`` or ``odom``), positions are metres, angles
radians (REP 103). Cells are ``(x, y)`` tuples: x counts columns, y rows, row 0 at the lowest y.
"""
from typing import List, Sequence, Tuple

import numpy as np

from mbot_slam_navigation import _core

Cell = Tuple[int, int]


class LogOddsModel:
    """How much one observation moves a cell, from hit and miss probabilities."""

    def __init__(self, p_hit: float = 0.7, p_miss: float = 0.4):
        self._impl = _core._LogOddsModel.from_probabilities(p_hit, p_miss)

    @property
    def hit(self) -> float:
        return self._impl.hit

    @property
    def miss(self) -> float:
        return self._impl.miss


class OccupancyGrid:
    """A log-odds occupancy grid; ``origin`` is the world corner of cell (0, 0) in metres."""

    def __init__(self, width: int, height: int, resolution: float, origin: Sequence[float] = (0.0, 0.0),
                 model: LogOddsModel = None):
        model = model or LogOddsModel()
        self._impl = _core._OccupancyGrid(int(width), int(height), float(resolution),
                                          np.asarray(origin, dtype=float), model._impl)

    @property
    def width(self) -> int:
        return self._impl.width

    @property
    def height(self) -> int:
        return self._impl.height

    @property
    def resolution(self) -> float:
        """Cell size [m]."""
        return self._impl.resolution

    @property
    def origin(self) -> Tuple[float, float]:
        """World position [m] of the outer corner of cell (0, 0)."""
        o = self._impl.origin
        return float(o[0]), float(o[1])

    def contains(self, cell: Cell) -> bool:
        return self._impl.contains(tuple(cell))

    def world_to_cell(self, x: float, y: float) -> Cell:
        return tuple(self._impl.world_to_cell(np.array([x, y], dtype=float)))

    def cell_center(self, cell: Cell) -> Tuple[float, float]:
        c = self._impl.cell_center(tuple(cell))
        return float(c[0]), float(c[1])

    def probability(self, cell: Cell) -> float:
        """Occupancy probability of a cell; raises IndexError outside the grid."""
        return self._impl.probability(tuple(cell))

    def observed(self, cell: Cell) -> bool:
        return self._impl.observed(tuple(cell))

    def set_occupied(self, cell: Cell, occupied: bool = True) -> None:
        """Marks a cell as certainly occupied (or free), e.g. to draw a known world."""
        self._impl.set_log_odds(tuple(cell), 100.0 if occupied else -100.0)

    def integrate_beam(self, start: Sequence[float], end: Sequence[float], hit: bool) -> None:
        self._impl.integrate_beam(np.asarray(start, float), np.asarray(end, float), bool(hit))

    def integrate_scan(self, pose: Sequence[float], angle_min: float, angle_increment: float,
                       range_min: float, range_max: float, ranges: Sequence[float],
                       usable_range: float) -> int:
        """Integrates a scan from a sensor at pose (x, y, yaw); returns the number of beams used."""
        return self._impl.integrate_scan(np.asarray(pose, float), angle_min, angle_increment,
                                         range_min, range_max, np.asarray(ranges, np.float32),
                                         usable_range)

    def grow_to_include(self, x: float, y: float, margin: float = 0.0) -> None:
        self._impl.grow_to_include(np.array([x, y], float), margin)

    def observed_count(self) -> int:
        return self._impl.observed_count()

    def ros_data(self) -> np.ndarray:
        """nav_msgs/OccupancyGrid values as a (height, width) int8 array: -1 unknown, 0..100."""
        return self._impl.ros_data()

    def cast_rays(self, x: float, y: float, angles: Sequence[float], max_range: float,
                  occupied_probability: float = 0.5) -> np.ndarray:
        """Distances [m] from (x, y) along each angle to the first occupied cell, +inf if none."""
        return _core._cast_rays(self._impl, np.array([x, y], float), np.asarray(angles, float),
                                float(max_range), occupied_probability)


def bresenham_line(start: Cell, end: Cell) -> List[Cell]:
    """Cells of the 8-connected line from start to end, both included."""
    return [tuple(c) for c in _core._bresenham_line(tuple(start), tuple(end))]


def make_room(width_m: float, height_m: float, resolution_m: float) -> OccupancyGrid:
    """A grid covering a width x height room plus one cell each side, with the walls' cells occupied
    (a test and benchmark scene)."""
    nx = int(round(width_m / resolution_m)) + 2
    ny = int(round(height_m / resolution_m)) + 2
    grid = OccupancyGrid(nx, ny, resolution_m, origin=(-resolution_m, -resolution_m))
    for x in range(nx):
        for y in range(ny):
            grid.set_occupied((x, y), x in (0, nx - 1) or y in (0, ny - 1))
    return grid
