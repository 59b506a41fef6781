"""The order of the frontiers, ROS-free: tour_order re-ranks the best frontiers by the shortest tour
through their goals (so that the robot finishes one side before it crosses to the other, and takes a
small frontier it passes rather than coming back for it)."""
from dataclasses import replace
from typing import List

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.frontiers import Frontier, Grid


def tour_order(frontiers: List[Frontier], passable: np.ndarray, costmap: Grid, potential_scale: float = 3.0,
               size: int = 20, block_m: float = 0.1) -> List[Frontier]:
    """The frontiers re-ranked by the tour they begin: each of the `size` best (by cost) costs
    potential_scale times the shortest path on from its goal through the goals of the other ones
    more, on top of its own cost (its path from the robot, its size), so that the robot finishes
    one side of the house before it crosses to the other, instead of leaving a small frontier behind
    and coming back for it (greedy choice; explore_lite's). Frontiers beyond the first `size` keep
    their cost plus the longest tour's, so they stay behind. size < 2 returns them unchanged.

    Distances between goals are path lengths over `passable` (rank_frontiers' stats['passable'])
    taken in blocks of block_m [m] (a block is passable if any cell of it is: two passable regions on
    either side of an obstacle lie at least twice the robot's inscribed radius apart, more than a
    block), which makes them a few times cheaper, and each search stops at the goals it is for
    (core.pathLengthsBetween). The tours are core.shortestPathsThroughAll's: exact up to 12 goals,
    within a few per cent beyond."""
    k = min(size, len(frontiers))
    if k < 2:
        return list(frontiers)
    best = sorted(frontiers, key=lambda f: f.cost)
    head, tail = best[:k], best[k:]
    b = max(1, int(round(block_m / costmap.resolution)))
    h, w = passable.shape
    pad = np.zeros(((h + b - 1) // b * b, (w + b - 1) // b * b), np.uint8)
    pad[:h, :w] = passable
    coarse = np.zeros((pad.shape[0] // b, pad.shape[1] // b), np.uint8)
    for i in range(b):  # the blocks' maximum, one offset within the block at a time
        for j in range(b):
            np.maximum(coarse, pad[i::b, j::b], out=coarse)
    cells = np.array([costmap.cell_of(f.goal[0], f.goal[1]) for f in head], int).reshape(-1, 2) // b
    inside = (cells[:, 0] >= 0) & (cells[:, 1] >= 0) & (cells[:, 0] < coarse.shape[0]) & (cells[:, 1] < coarse.shape[1])
    d = np.full((k, k), -1.0)
    idx = np.flatnonzero(inside)
    if len(idx):
        d[np.ix_(idx, idx)] = _core._path_lengths_between(coarse, cells[idx, 0], cells[idx, 1]) * (b * costmap.resolution)
    # not connected on the coarse grid (a goal in a block of its own, a goal off this grid found on
    # a costmap of another cycle): no path known, via the robot
    via_robot = np.array([f.path_m for f in head])[:, None] + np.array([f.path_m for f in head])[None, :]
    d = np.where(d >= 0, d, via_robot)
    np.fill_diagonal(d, 0.0)
    rest = _core._shortest_paths_through_all(d)
    out = [replace(f, cost=f.cost + potential_scale * float(rest[i])) for i, f in enumerate(head)]
    worst = potential_scale * float(rest.max())
    out += [replace(f, cost=f.cost + worst) for f in tail]
    return sorted(out, key=lambda f: f.cost)
