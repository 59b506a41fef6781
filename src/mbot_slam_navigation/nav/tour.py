"""The order of the frontiers, ROS-free: tour_order re-ranks the best frontiers by the shortest tour
through their goals (so that the robot finishes one side before it crosses to the other, and takes a
small frontier it passes rather than coming back for it); GoalFields keeps the path-length fields
from the goals between planning cycles."""
import math
from dataclasses import replace
from typing import List, Optional, Tuple

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.frontiers import Frontier, Grid


class GoalFields:
    """Path-length fields from frontier goals over tour_order's coarse grid, kept between planning
    cycles so that a cycle computes the fields of new goals only (a field is a Dijkstra over the
    whole floor: 0.5-1 ms on the office's coarse grid, and a tour through 20 goals needs 19 or 20).

    A field serves for max_age [s] (the map grows under it: a way found since then is not in it),
    and for any goal within reuse_m [m] by path of the goal it was computed from (a frontier's goal
    moves as the robot does); the path lengths it gives are then off by at most reuse_m."""

    def __init__(self, max_age: float = 10.0, reuse_m: float = 0.3):
        self.max_age, self.reuse_m = max_age, reuse_m
        # (time, field [blocks], origin [m] of block (0, 0), block size [m])
        self._fields: List[Tuple[float, np.ndarray, Tuple[float, float], float]] = []
        self.computed = 0  # fields computed so far (for tests and the log)

    @staticmethod
    def length_at(entry, x: float, y: float) -> float:
        """[m] the path length the field gives at (x, y); -1 if it has none there."""
        _, lengths, (ox, oy), step = entry
        r, c = int(math.floor((y - oy) / step)), int(math.floor((x - ox) / step))
        if not (0 <= r < lengths.shape[0] and 0 <= c < lengths.shape[1]) or lengths[r, c] < 0:
            return -1.0
        return float(lengths[r, c]) * step

    def cached(self, now: float, goal: Tuple[float, float]):
        """A field that serves `goal` now, or None."""
        self._fields = [e for e in self._fields if 0.0 <= now - e[0] < self.max_age]
        best, best_d = None, math.inf
        for e in self._fields:
            v = self.length_at(e, goal[0], goal[1])
            if 0.0 <= v <= self.reuse_m and v < best_d:
                best, best_d = e, v
        return best

    def compute(self, now: float, coarse: np.ndarray, origin: Tuple[float, float], step: float,
                cell: Tuple[int, int]):
        self.computed += 1
        entry = (now, _core._path_lengths(coarse, cell[1], cell[0]), origin, step)
        self._fields.append(entry)
        return entry


def tour_order(frontiers: List[Frontier], passable: np.ndarray, costmap: Grid, potential_scale: float = 3.0,
               size: int = 20, block_m: float = 0.1, fields: Optional[GoalFields] = None,
               now: float = 0.0) -> List[Frontier]:
    """The frontiers re-ranked by the tour they begin: each of the `size` best (by cost) costs
    potential_scale times the shortest path on from its goal through the goals of the other ones
    more, on top of its own cost (its path from the robot, its size), so that the robot finishes
    one side of the house before it crosses to the other, instead of leaving a small frontier behind
    and coming back for it (greedy choice; explore_lite's). Frontiers beyond the first `size` keep
    their cost plus the longest tour's, so they stay behind. size < 2 returns them unchanged.

    Distances between goals are path lengths over `passable` (rank_frontiers' stats['passable'])
    taken in blocks of block_m [m] (a block is passable if any cell of it is: two passable regions on
    either side of an obstacle lie at least twice the robot's inscribed radius apart, more than a
    block), which makes them a few times cheaper; with `fields` (kept by the caller between cycles,
    `now` [s] its clock) a goal's path lengths are reused while they serve (GoalFields). The tours
    are core.shortestPathsThroughAll's: exact up to 12 goals, within a few per cent beyond."""
    k = min(size, len(frontiers))
    if k < 2:
        return list(frontiers)
    if fields is None:
        fields = GoalFields()
    best = sorted(frontiers, key=lambda f: f.cost)
    head, tail = best[:k], best[k:]
    b = max(1, int(round(block_m / costmap.resolution)))
    h, w = passable.shape
    pad = np.zeros(((h + b - 1) // b * b, (w + b - 1) // b * b), np.uint8)
    pad[:h, :w] = passable
    coarse = pad.reshape(pad.shape[0] // b, b, pad.shape[1] // b, b).max(axis=(1, 3))
    step = b * costmap.resolution
    cells = []
    for f in head:
        r, c = costmap.cell_of(f.goal[0], f.goal[1])
        cells.append((int(r) // b, int(c) // b))
    inside = [0 <= r < coarse.shape[0] and 0 <= c < coarse.shape[1] for r, c in cells]
    rows = [fields.cached(now, f.goal) for f in head]
    for i in range(k):
        if rows[i] is None and inside[i]:
            rows[i] = fields.compute(now, coarse, costmap.origin, step, cells[i])
    d = np.zeros((k, k))
    for i in range(k):
        for j in range(i + 1, k):
            values = [GoalFields.length_at(rows[a], head[z].goal[0], head[z].goal[1])
                      for a, z in ((i, j), (j, i)) if rows[a] is not None]
            values = [v for v in values if v >= 0]
            # not connected on the coarse grid (a goal in a block of its own, a goal off this grid
            # found on a costmap of another cycle): no path known, via the robot
            d[i, j] = d[j, i] = min(values) if values else head[i].path_m + head[j].path_m
    rest = _core._shortest_paths_through_all(d)
    out = [replace(f, cost=f.cost + potential_scale * float(rest[i])) for i, f in enumerate(head)]
    worst = potential_scale * float(rest.max())
    out += [replace(f, cost=f.cost + worst) for f in tail]
    return sorted(out, key=lambda f: f.cost)
