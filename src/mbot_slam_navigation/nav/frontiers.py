"""Frontier exploration, ROS-free: where the map ends, which of those places the robot can reach,
and which one to go to next (the explore node's decisions, kept here so they can be tested).

Grids are nav_msgs/OccupancyGrid-like: `data` (rows = y from the origin up, cols = x), -1 unknown,
0..100 occupancy; `origin` is the world corner [m] of cell (0, 0); everything in the map frame.

A frontier cell is a known cell that is not occupied (any value from 0 up to `occupied_min`, so
probabilistic maps work too) with an unknown 4-neighbour. Frontier cells group 8-connected; a group
shorter than `min_frontier_size` [m] (cells x resolution, as explore_lite measures it) is ignored.
The goal of a frontier is its cell nearest to the robot by path on the global costmap (cells below
the inscribed cost, known), never its centroid, which may lie inside a wall.
"""
import math
from dataclasses import dataclass, field, replace
from typing import List, Optional, Sequence, Tuple

import cv2
import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.maps.map_io import SAVER_OCCUPIED

# explore's defaults (explore.read_parameters reads them; explore_lite's values)
MIN_FRONTIER_SIZE = 0.75  # [m]
POTENTIAL_SCALE, GAIN_SCALE = 3.0, 1.0
COST_INSCRIBED = 99  # costmap_2d's OccupancyGrid translation: 99 inscribed, 100 lethal, -1 unknown


@dataclass
class Grid:
    data: np.ndarray                 # (rows, cols) occupancy or cost
    resolution: float                # [m/cell]
    origin: Tuple[float, float]      # [m] world corner of cell (0, 0)

    def cell_of(self, x, y):
        """(row, col) arrays of the cells holding world points (x, y) [m] (may lie outside)."""
        return (np.floor((np.asarray(y) - self.origin[1]) / self.resolution).astype(int),
                np.floor((np.asarray(x) - self.origin[0]) / self.resolution).astype(int))

    def centre_of(self, rows, cols):
        """World (x, y) [m] of cell centres."""
        return (self.origin[0] + (np.asarray(cols) + 0.5) * self.resolution,
                self.origin[1] + (np.asarray(rows) + 0.5) * self.resolution)

    def inside(self, rows, cols):
        return (rows >= 0) & (cols >= 0) & (rows < self.data.shape[0]) & (cols < self.data.shape[1])


GAIN_RADIUS = 1.0  # [m] around a frontier's cells: the unknown space it borders (Frontier.unknown_m2)
SHADOW_EDGE = 1.3  # [m] an enclosed unknown region with a connected piece of open rim this wide is floor


@dataclass
class Frontier:
    cells: np.ndarray        # (N, 2) world x, y [m] of its cells
    size_m: float            # N x resolution
    goal: Tuple[float, float]
    path_m: float            # path length from the robot to the goal [m]
    cost: float              # potential_scale * path_m - gain_scale * min(size_m, gain_size_max) (lower is better)
    unknown_m2: float = math.inf  # [m^2] unknown space within GAIN_RADIUS of its cells (what it may show)


@dataclass
class GivenUp:
    """A frontier the explorer will not send the robot to, and why (for the report)."""
    x: float                 # [m] centroid of its cells, map frame
    y: float
    size_m: float
    why: str

    def as_dict(self) -> dict:
        return {'x': round(self.x, 2), 'y': round(self.y, 2), 'size_m': round(self.size_m, 2), 'why': self.why}


def frontier_groups(m: Grid, occupied_min: int = SAVER_OCCUPIED, min_unknown_area: float = 0.0) -> List[np.ndarray]:
    """The frontiers of map m as arrays of (row, col), largest first (see unknown_space)."""
    return _frontier_groups(m, unknown_space(m, occupied_min, min_unknown_area), occupied_min)


def unknown_space(m: Grid, occupied_min: int = SAVER_OCCUPIED, min_unknown_area: float = 0.0) -> np.ndarray:
    """The cells of map m (uint8 mask) whose unknown space is there to explore.

    Unknown space that the map encloses (not reaching its edge) and smaller than min_unknown_area
    [m^2] does not make frontiers when walls bound most of it: it is the inside of furniture or a
    pillar, which no sensor sees. Enclosed unknown space bounded mostly by free cells, and of at
    least a tenth of min_unknown_area, still does: it is floor in a shadow (the part of a room
    beside its door that the robot did not see from the doorway; measured: the home's kitchen left
    71% mapped, its shadow of about 1.5 m^2 taken for furniture). So does one with a connected
    piece of open rim SHADOW_EDGE across: a shadow's edge is one line of floor, and a corner's
    shadow against two walls has only 41-50% of its rim open (the kitchen's corner: 38% in cells,
    its edge 1.4-2.6 m; the home's table and bathroom object, seen round, 1.0-1.2 m).
    """
    data = m.data.astype(np.int16)
    unknown = (data < 0).astype(np.uint8)
    open_known = (data >= 0) & (data < occupied_min)
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    if min_unknown_area > 0 and unknown.any():
        n, labels, stats, _ = cv2.connectedComponentsWithStats(unknown, connectivity=8)
        h, w = unknown.shape
        x, y, bw, bh, area = (stats[:, i] for i in range(5))
        at_edge = (x == 0) | (y == 0) | (x + bw == w) | (y + bh == h)
        keep = at_edge | (area * m.resolution ** 2 >= min_unknown_area)
        keep[0] = False  # label 0: the known cells
        shadow = ~keep & (area * m.resolution ** 2 >= 0.1 * min_unknown_area)
        shadow[0] = False
        for i in np.flatnonzero(shadow):
            # the known cells around it, in its bounding box grown by a cell (it is enclosed, so
            # never at the grid's edge)
            r0, c0, r1, c1 = y[i] - 1, x[i] - 1, y[i] + bh[i] + 1, x[i] + bw[i] + 1
            inside = (labels[r0:r1, c0:c1] == i).astype(np.uint8)
            ring = (cv2.dilate(inside, cross) > 0) & (inside == 0)
            open_rim = ring & open_known[r0:r1, c0:c1]
            keep[i] = (np.count_nonzero(open_rim) >= 0.5 * np.count_nonzero(ring)
                       or _longest_piece(open_rim) * m.resolution >= SHADOW_EDGE)
        unknown = keep[labels].astype(np.uint8)
    return unknown


def _longest_piece(mask: np.ndarray) -> float:
    """[cells] the largest extent (bounding-box diagonal) of an 8-connected piece of mask."""
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    return float(np.max(np.hypot(stats[1:, 2], stats[1:, 3]))) if n > 1 else 0.0


def _frontier_groups(m: Grid, unknown: np.ndarray, occupied_min: int) -> List[np.ndarray]:
    data = m.data.astype(np.int16)
    open_known = (data >= 0) & (data < occupied_min)
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    frontier = (open_known & (cv2.dilate(unknown, cross) > 0)).astype(np.uint8)
    n, labels = cv2.connectedComponents(frontier, connectivity=8)
    # one pass over the labelled cells, split by label (not one scan of the grid per group)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    order = np.argsort(lab, kind='stable')
    rows, cols, lab = rows[order], cols[order], lab[order]
    splits = np.flatnonzero(np.diff(lab)) + 1
    groups = [np.column_stack([r, c]) for r, c in zip(np.split(rows, splits), np.split(cols, splits)) if len(r)]
    return sorted(groups, key=len, reverse=True)


def passable(costmap: Grid, m: Grid, occupied_min: int = SAVER_OCCUPIED) -> np.ndarray:
    """Costmap cells the robot's centre may cross: cost below inscribed, and known and not occupied
    in the map (the costmap may count unknown space as free)."""
    cost = costmap.data.astype(np.int16)
    ok = (cost >= 0) & (cost < COST_INSCRIBED)
    if (m.data.shape == cost.shape and m.resolution == costmap.resolution
            and np.allclose(m.origin, costmap.origin, atol=1e-6 * m.resolution)):
        v = m.data.astype(np.int16)  # the usual case: the global costmap is laid on the map
        return ok & (v >= 0) & (v < occupied_min)
    rows, cols = np.indices(cost.shape)
    x, y = costmap.centre_of(rows, cols)
    mr, mc = m.cell_of(x, y)
    inside = m.inside(mr, mc)
    known_open = np.zeros_like(ok)
    v = m.data[mr[inside], mc[inside]].astype(np.int16)
    known_open[inside] = (v >= 0) & (v < occupied_min)
    return ok & known_open


def _sees(cost: np.ndarray, rows: np.ndarray, cols: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """For each costmap cell (rows[i], cols[i]), whether it sees the nearest of `cells` ((N, 2)
    rows, cols): no lethal cell on the straight line between them (sampled every half cell or
    finer). A goal across a wall from its frontier (0.4 m from a frontier cell, through a 5 cm
    wall) shows the robot nothing of it."""
    rows, cols = np.asarray(rows, int), np.asarray(cols, int)
    d2 = (rows[:, None] - cells[None, :, 0]) ** 2 + (cols[:, None] - cells[None, :, 1]) ** 2
    nearest = cells[np.argmin(d2, axis=1)]
    dr, dc = nearest[:, 0] - rows, nearest[:, 1] - cols
    t = np.linspace(0.0, 1.0, 2 * int(np.max(np.maximum(np.abs(dr), np.abs(dc)), initial=0)) + 1)
    r = np.rint(rows[:, None] + t[None, :] * dr[:, None]).astype(int)
    c = np.rint(cols[:, None] + t[None, :] * dc[:, None]).astype(int)
    return ~np.any(cost[r, c] >= 100, axis=1)


def rank_frontiers(m: Grid, costmap: Grid, robot: Tuple[float, float], min_frontier_size: float = MIN_FRONTIER_SIZE,
                   potential_scale: float = POTENTIAL_SCALE, gain_scale: float = GAIN_SCALE, avoid: Sequence[Tuple[float, float]] = (),
                   avoid_radius: float = 0.6, goal_reach: float = 0.4, goal_cost_max: int = 50,
                   occupied_min: int = SAVER_OCCUPIED, min_unknown_area: float = 0.0, escape_radius: float = 0.35,
                   stats: Optional[dict] = None, avoid_goals: Sequence[Tuple[float, float]] = (),
                   unreachable: Optional[List[GivenUp]] = None,
                   keep_goal: Optional[Tuple[float, float]] = None,
                   min_unknown_beside: float = 0.0, gain_size_max: float = 0.0) -> List[Frontier]:
    """Reachable frontiers, best (lowest cost) first.

    Frontier cells within avoid_radius [m] of a point in `avoid` (places blacklisted or already
    visited) do not count. A frontier's goal is the costmap cell nearest to the robot by path among
    those within goal_reach [m] of its cells with a cost below goal_cost_max (OccupancyGrid scale,
    0..100: clear of the inflated zone, so move_base will not refuse it as occupied when the
    obstacle behind the frontier shows up), and not within avoid_radius of a point in
    `avoid_goals` (goals that failed, or where the robot stood with the frontier still there:
    whatever shape the frontier has now, that goal is not sent again), and seeing the frontier
    (_sees: not across a wall from it). Frontiers large enough but with no such cell, or large
    enough only with the cells near `avoid`, are appended to `unreachable`, with why. A frontier for which `keep_goal` (the goal
    being driven to) is still such a cell keeps it as its goal: the cell nearest by path changes
    as the robot moves, and a goal that jumps from one end of a frontier to the other and back
    sends the robot to and fro (measured: 1.1 m apart, every 10-20 s, for 90 s at the home's
    last frontier). A frontier with less than min_unknown_beside [m^2] of unknown space within
    GAIN_RADIUS of its cells (Frontier.unknown_m2; beyond the grid's edge counts as unknown) goes to
    `unreachable` too: it is not worth a trip.

    A frontier's size counts in its cost up to gain_size_max [m] (0: no cap). Uncapped, the edge of
    the laser's view down a corridor (60 m of frontier in the office, seen from its lobby) outweighs
    20 m of path, and the lobby behind the robot was left for last: 13-19 m back across the floor at
    the end, plateaus of 67 and 113 s.
    """
    rr, rc = costmap.cell_of(robot[0], robot[1])
    if not costmap.inside(rr, rc):
        if stats is not None:
            stats['robot_outside'] = True  # the costmap has not grown to the robot yet
        return []
    open_cells = passable(costmap, m, occupied_min)
    cost = costmap.data.astype(np.int16)
    # Within escape_radius of the robot, any cell short of lethal is passable: a robot that stands
    # in the inscribed zone (an obstacle appeared beside it) can still back out, as move_base does.
    rows, cols = np.ogrid[:cost.shape[0], :cost.shape[1]]
    around = (rows - rr) ** 2 + (cols - rc) ** 2 <= (escape_radius / costmap.resolution) ** 2
    open_cells = open_cells | (around & (cost >= 0) & (cost < 100))
    dist = _core._path_lengths(open_cells.astype(np.uint8), int(rc), int(rr))
    if stats is not None:
        stats['reachable_m2'] = float(np.count_nonzero(dist >= 0)) * costmap.resolution ** 2
        stats['passable'] = open_cells  # for tour_order
    reach_ok = (dist >= 0) & open_cells & (cost < goal_cost_max)
    goal_ok = reach_ok
    avoid_goals = np.asarray(avoid_goals, float).reshape(-1, 2)
    if len(avoid_goals):
        blocked = np.zeros(cost.shape, np.uint8)
        r = max(1, int(round(avoid_radius / costmap.resolution)))
        for gx, gy in avoid_goals:
            br, bc = costmap.cell_of(gx, gy)
            cv2.circle(blocked, (int(bc), int(br)), r, 1, -1)
        goal_ok = reach_ok & (blocked == 0)
    k = 2 * int(math.ceil(goal_reach / costmap.resolution)) + 1
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    avoid = np.asarray(avoid, float).reshape(-1, 2)
    kr, kc = costmap.cell_of(*keep_goal) if keep_goal is not None else (-1, -1)
    unknown = unknown_space(m, occupied_min, min_unknown_area)
    g_reach = int(math.ceil(GAIN_RADIUS / m.resolution))
    g_disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * g_reach + 1, 2 * g_reach + 1))
    # beyond the grid's edge is unknown too (the SLAM map grows as the robot sees more)
    unknown_beyond = cv2.copyMakeBorder(unknown, g_reach, g_reach, g_reach, g_reach, cv2.BORDER_CONSTANT, value=1)
    out = []
    for g in _frontier_groups(m, unknown, occupied_min):
        x, y = m.centre_of(g[:, 0], g[:, 1])
        if len(x) * m.resolution < min_frontier_size:
            continue
        if len(avoid):
            keep = np.min(np.hypot(x[:, None] - avoid[None, :, 0], y[:, None] - avoid[None, :, 1]), axis=1) >= avoid_radius
            if keep.sum() * m.resolution < min_frontier_size:
                if unreachable is not None:
                    unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), len(x) * m.resolution,
                                               'too little of it (%.2f m) lies farther than %.1f m from places '
                                               'visited or given up' % (keep.sum() * m.resolution, avoid_radius)))
                continue
            x, y, g = x[keep], y[keep], g[keep]
        # the unknown space it borders, within GAIN_RADIUS of its cells (in a window around it;
        # unknown_beyond's cell (r + g_reach, c + g_reach) is the map's (r, c))
        ur0, uc0 = int(g[:, 0].min()), int(g[:, 1].min())
        ur1, uc1 = int(g[:, 0].max()) + 2 * g_reach + 1, int(g[:, 1].max()) + 2 * g_reach + 1
        cells = np.zeros((ur1 - ur0, uc1 - uc0), np.uint8)
        cells[g[:, 0] - ur0 + g_reach, g[:, 1] - uc0 + g_reach] = 1
        unknown_m2 = float(np.count_nonzero((cv2.dilate(cells, g_disc) > 0) & (unknown_beyond[ur0:ur1, uc0:uc1] > 0))
                           ) * m.resolution ** 2
        size = len(x) * m.resolution
        if unknown_m2 < min_unknown_beside:
            # a sliver the laser grazed: a trip there shows next to nothing (measured: the office's
            # end game turned back 26 s into a 19 m trip for 0.1 m^2, and the trip took 70 s more)
            if unreachable is not None:
                unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), size,
                                           'only %.2f m^2 unknown within %.1f m of it (min_unknown_beside %.2f m^2)'
                                           % (unknown_m2, GAIN_RADIUS, min_unknown_beside)))
            continue
        cr, cc = costmap.cell_of(x, y)
        inside = costmap.inside(cr, cc)
        # the cells within goal_reach of the frontier, in a window around it (not the whole grid)
        half = k // 2
        r0, c0 = max(int(cr.min()) - half, 0), max(int(cc.min()) - half, 0)
        r1, c1 = min(int(cr.max()) + half + 1, cost.shape[0]), min(int(cc.max()) + half + 1, cost.shape[1])
        candidates = reachable = np.zeros((max(r1 - r0, 0), max(c1 - c0, 0)), bool)
        if inside.any() and candidates.size:
            near = np.zeros(candidates.shape, np.uint8)
            near[cr[inside] - r0, cc[inside] - c0] = 1
            reachable = (cv2.dilate(near, disc) > 0) & reach_ok[r0:r1, c0:c1]
            candidates = reachable & goal_ok[r0:r1, c0:c1]
        if not candidates.any():
            if unreachable is not None:
                why = ('its only goals lie within %.1f m of goals that failed or where the robot stood with it '
                       'still there' % avoid_radius if reachable.any() else
                       'unreachable: no cell within %.1f m of it that the robot can reach clear of obstacles on the '
                       'global costmap' % goal_reach)
                unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), size, why))
            continue
        d = np.where(candidates, dist[r0:r1, c0:c1], np.inf)
        fcells = np.column_stack([cr[inside], cc[inside]])
        # an obstacle the costmap has on a frontier cell (seen since the map was made) blocks no view
        # of the others
        clear = cost[fcells[:, 0], fcells[:, 1]] < 100
        if clear.any():
            fcells = fcells[clear]
        if (r0 <= kr < r1 and c0 <= kc < c1 and candidates[kr - r0, kc - c0]
                and _sees(cost, [kr], [kc], fcells)[0]):
            gr, gc = int(kr), int(kc)
        else:
            # the nearest by path that sees the frontier, tried 32 at a time (the window of a long
            # frontier holds 10^5 cells, too many to sort every cycle; measured in the office: in
            # 4 cycles of 10 the first one tried is across a wall, a corridor's cells beside a room)
            gr = gc = -1
            flat, left = d.ravel(), int(np.count_nonzero(candidates))
            while gr < 0 and left > 0:
                n_try = min(32, left)
                batch = np.argpartition(flat, n_try - 1)[:n_try] if n_try < flat.size else np.arange(flat.size)
                batch = batch[np.argsort(flat[batch])]
                br, bc = np.unravel_index(batch, d.shape)
                ok = np.flatnonzero(_sees(cost, br + r0, bc + c0, fcells) & np.isfinite(flat[batch]))
                if len(ok):
                    gr, gc = int(br[ok[0]] + r0), int(bc[ok[0]] + c0)
                else:
                    flat[batch] = np.inf
                left -= n_try
            if gr < 0:
                if unreachable is not None:
                    unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), size,
                                               'unreachable: every cell within %.1f m of it that the robot can '
                                               'reach lies across a wall from it' % goal_reach))
                continue
        gx, gy = costmap.centre_of(gr, gc)
        path_m = float(d[gr - r0, gc - c0]) * costmap.resolution
        gain = min(size, gain_size_max) if gain_size_max > 0 else size
        out.append(Frontier(np.column_stack([x, y]), size, (float(gx), float(gy)), path_m,
                            potential_scale * path_m - gain_scale * gain, unknown_m2))
    return sorted(out, key=lambda f: f.cost)


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


@dataclass
class Blacklisted:
    """A place not to send the robot to: a goal reached (for good), or goals that failed on one
    frontier (until `until`, for good after max_tries)."""
    goals: List[Tuple[float, float]]  # [m] the goals sent there (map frame)
    until: float                      # [s] when it may be tried again
    tries: int                        # how many times a goal here failed
    cells: Optional[np.ndarray] = None  # (N, 2) [m] the frontier's cells then (None: its frontier vanished)
    size_m: float = 0.0
    why: str = ''                     # the last failure's reason
    reached: bool = False             # the robot got to the goal (not a failure)


def _near_fraction(a: np.ndarray, b: np.ndarray, distance: float) -> float:
    """Fraction of the points of a within `distance` [m] of some point of b."""
    if len(a) == 0 or len(b) == 0:
        return 0.0
    # most pairs lie far apart (a frontier and a place blacklisted across the floor): their boxes tell
    if np.any(a.min(axis=0) > b.max(axis=0) + distance) or np.any(b.min(axis=0) > a.max(axis=0) + distance):
        return 0.0
    step = max(1, len(b) // 400)  # a subsample of b is enough at cell spacing; bounds the cost
    bb = b[::step]
    near = np.zeros(len(a), bool)
    for i in range(0, len(a), 512):
        chunk = a[i:i + 512]
        d2 = (chunk[:, None, 0] - bb[None, :, 0]) ** 2 + (chunk[:, None, 1] - bb[None, :, 1]) ** 2
        near[i:i + 512] = d2.min(axis=1) <= (distance + step * 0.05) ** 2
    return float(near.mean())


@dataclass
class ExploreState:
    """What the explorer decides between planning cycles. Times are seconds of ROS time."""
    progress_timeout: float = 30.0    # [s] without moving progress_distance: the goal is given up
    progress_distance: float = 0.2    # [m]
    blacklist_timeout: float = 60.0   # [s] before a failed goal may be tried again
    max_tries: int = 2                # failures after which a place stays blacklisted
    blacklist_radius: float = 0.6     # [m] around a failed or visited goal
    same_frontier_overlap: float = 0.5  # fraction of cells within 0.3 m that makes two frontiers one
    hysteresis: float = 1.0           # [cost] a new frontier must beat the current goal's by this
    settle_time: float = 10.0         # [s] at most to wait for a map made after a goal was reached
    max_goals_per_place: int = 5      # new goals within blacklist_radius of one place before it is given up
    switch_back_after: float = 60.0   # [s] before a goal left for a better one may beat the current goal
    goal: Optional[Frontier] = None
    progress_at: Tuple[float, float] = (math.nan, math.nan)
    progress_time: float = 0.0
    blacklist: List[Blacklisted] = field(default_factory=list)
    goals_chosen: int = 0             # new goals (a goal that moved with its frontier is not new)
    places: List[List[float]] = field(default_factory=list)  # [x, y, new goals sent there]
    why: str = ''                     # why choose() last chose a new goal (for the log)
    left: List[Tuple[float, float, float]] = field(default_factory=list)  # [x, y, when] goals left for better ones

    def avoid(self, now: float) -> List[Tuple[float, float]]:
        """Places whose frontier cells do not count now (rank_frontiers' avoid): goals reached, and
        goals that failed while blacklisted (for good after max_tries)."""
        return [g for b in self.blacklist if b.reached or b.until > now or b.tries >= self.max_tries for g in b.goals]

    def avoid_for_good(self) -> List[Tuple[float, float]]:
        """Places whose frontier cells never count again: goals that failed max_tries times. Cells
        near a goal reached are left out only while other frontiers remain (so that the robot does
        not turn back to a place it has been, where the map flickers); when nothing else is left,
        they are what there is to explore (a room seen only from its door whose frontier came back
        when the map was corrected). max_goals_per_place bounds the trips there."""
        return [g for b in self.blacklist if not b.reached and b.tries >= self.max_tries for g in b.goals]

    def avoid_goals(self, now: float) -> List[Tuple[float, float]]:
        """Goals that may not be sent now (rank_frontiers' avoid_goals): those that failed, while
        blacklisted, and those the robot stood at with its frontier still there. From where the robot
        stood, it saw that frontier as it is; the same spot shows nothing more, so the frontier's next
        goal lies at least blacklist_radius away (measured: the home's kitchen, a shadow beside its
        door seen from the doorway, got its goal in the doorway five times and was given up, 66%
        mapped)."""
        return [g for b in self.blacklist if b.cells is not None
                and (b.reached or b.until > now or b.tries >= self.max_tries) for g in b.goals]

    def _goals_sent_near(self, goal: Tuple[float, float]) -> int:
        return sum(int(p[2]) for p in self.places
                   if math.hypot(p[0] - goal[0], p[1] - goal[1]) < self.blacklist_radius)

    def _same_place(self, b: Blacklisted, f: Frontier) -> bool:
        if b.cells is None:
            return False
        # A goal near a failed one is the same place; near a reached one it may see more: there
        # only the same cells make the same frontier.
        if not b.reached and any(math.hypot(f.goal[0] - x, f.goal[1] - y) < self.blacklist_radius for x, y in b.goals):
            return True
        return (_near_fraction(f.cells, b.cells, 0.3) >= self.same_frontier_overlap or
                _near_fraction(b.cells, f.cells, 0.3) >= self.same_frontier_overlap)

    def screen(self, now: float, frontiers: List[Frontier],
               map_time: float = math.inf) -> Tuple[List[Frontier], int, List[GivenUp]]:
        """(frontiers that may be sent now, how many wait, those given up for good) by the failures
        recorded: a frontier that is the place of a failed goal (its goal near that goal, or most of
        its cells near the failed frontier's cells, however it has grown or shrunk since) waits
        blacklist_timeout, and is given up after max_tries failures. A frontier still there at a
        goal reached is given up only on a map made after the robot got there (map_time [s], the
        stamp of the map the frontiers come from); until then it waits, settle_time at most."""
        eligible, waiting, given_up = [], 0, []
        failures = [b for b in self.blacklist if b.cells is not None]
        for f in frontiers:
            sent = self._goals_sent_near(f.goal)
            if sent >= self.max_goals_per_place:
                # Chosen again and again and never explored (two frontiers pulling the robot to and
                # fro): a bound on goals per place is what makes every exploration end.
                x, y = f.cells.mean(axis=0)
                given_up.append(GivenUp(float(x), float(y), f.size_m, 'sent %d times and never explored' % sent))
                continue
            matches = [b for b in failures if self._same_place(b, f)]
            # with no newer map within settle_time (SLAM publishes none while the robot stands
            # still), it is judged on the map there is
            unsettled = [b for b in matches if b.reached and map_time <= b.until and now - b.until < self.settle_time]
            exhausted = [b for b in matches if b.tries >= self.max_tries and b not in unsettled]
            if exhausted:
                x, y = f.cells.mean(axis=0)
                b = exhausted[0]
                given_up.append(GivenUp(float(x), float(y), f.size_m, b.why if b.reached else
                                        '%d goals failed (last: %s)' % (b.tries, b.why)))
            elif unsettled or any(b.until > now and not b.reached for b in matches):
                waiting += 1
            else:
                eligible.append(f)
        return eligible, waiting, given_up

    def choose(self, now: float, frontiers: List[Frontier], robot: Tuple[float, float]) -> Optional[Frontier]:
        """The frontier to head for (a goal to send), or None to keep the current goal; with no
        frontiers the current goal's place counts as visited and there is no goal."""
        self.why = 'no goal before'
        if not frontiers:
            self.reached(now)
            return None
        best = frontiers[0]
        if self.goal is not None:
            # The frontier being explored, if still there: the one with cells nearest the goal sent
            # (its cells and goal shift as the map grows; matching on cells keeps the robot from
            # flipping between two frontiers whose goals move).
            gx, gy = self.goal.goal
            near = [(float(np.min(np.hypot(f.cells[:, 0] - gx, f.cells[:, 1] - gy))), i) for i, f in enumerate(frontiers)]
            d, i = min(near)
            current = [frontiers[i]] if d < 1.0 else []
            if not current:
                # Its frontier is gone (mapped on the way, or below min_frontier_size now): the place
                # counts as visited, so that a frontier flickering there does not pull the robot back.
                self.why = 'the frontier of (%.2f, %.2f) is gone' % (gx, gy)
                self.reached(now)
            else:
                self.why = 'cost %.1f against %.1f for (%.2f, %.2f)' % (best.cost, current[0].cost, gx, gy)
            # A goal left for a better one does not take the robot back from the current one for
            # switch_back_after: as the map grows, the costs of two frontiers can take turns
            # (measured: the home's kitchen and hall swapped 4 times in 30 s, and the robot reached
            # neither for 88 s).
            self.left = [g for g in self.left if now - g[2] < self.switch_back_after]
            left_before = any(math.hypot(best.goal[0] - x, best.goal[1] - y) < self.blacklist_radius
                              for x, y, _ in self.left)
            if current and (best.cost > current[0].cost - self.hysteresis or left_before):
                if math.hypot(current[0].goal[0] - self.goal.goal[0], current[0].goal[1] - self.goal.goal[1]) < 0.25:
                    return None
                # The same frontier, but its goal moved (the map grew, or an obstacle appeared near
                # the old goal): follow it without counting a new goal.
                self.goal = current[0]
                return current[0]
            if current:
                self.left.append((gx, gy, now))
        if self.goal is not None and math.hypot(best.goal[0] - self.goal.goal[0], best.goal[1] - self.goal.goal[1]) < 0.25:
            # Another frontier whose goal is the one being driven to (two groups of cells that one
            # cell serves): not a new goal, and not one more goal sent to that place.
            self.goal = best
            return None
        self.goal = best
        self.goals_chosen += 1
        for p in self.places:
            if math.hypot(p[0] - best.goal[0], p[1] - best.goal[1]) < self.blacklist_radius:
                p[2] += 1
                break
        else:
            self.places.append([best.goal[0], best.goal[1], 1])
        self.progress_at, self.progress_time = robot, now
        return best

    def stuck(self, now: float, robot: Tuple[float, float]) -> bool:
        """True when the robot has not moved progress_distance within progress_timeout while a goal
        is active; the goal is then blacklisted and dropped."""
        if self.goal is None:
            return False
        if math.hypot(robot[0] - self.progress_at[0], robot[1] - self.progress_at[1]) >= self.progress_distance:
            self.progress_at, self.progress_time = robot, now
            return False
        if now - self.progress_time > self.progress_timeout:
            self.fail(now, 'no progress for %.0f s' % self.progress_timeout)
            return True
        return False

    def fail(self, now: float, why: str = '') -> None:
        """The current goal failed (aborted by move_base, or no progress): blacklist its place and
        its frontier."""
        if self.goal is None:
            return
        f = self.goal
        for b in self.blacklist:
            if b.cells is not None and not b.reached and self._same_place(b, f):
                b.tries += 1
                b.until = now + self.blacklist_timeout
                b.goals.append(f.goal)
                b.cells = np.concatenate([b.cells, f.cells])
                b.size_m, b.why = f.size_m, why
                break
        else:
            self.blacklist.append(Blacklisted([f.goal], now + self.blacklist_timeout, 1, f.cells.copy(), f.size_m, why))
        self.goal = None

    def reached(self, now: float, arrived: bool = False, seen_radius: float = 1.5) -> None:
        """The goal's place is not sent again: its frontier vanished on the way, or (arrived) the
        robot got there. Frontier cells within seen_radius [m] of a goal the robot stood at, and
        still there, cannot be seen from the floor (the gap behind a bathtub, under furniture): a
        frontier made mostly of those, reached max_tries times, is given up, not chased goal after
        goal along its cells (once is not enough: at a doorway a step more may show the room). A
        long frontier of which the robot saw one end (a hall beyond laser range) is not."""
        if self.goal is not None:
            cells = None
            if arrived:
                c = self.goal.cells
                near = np.hypot(c[:, 0] - self.goal.goal[0], c[:, 1] - self.goal.goal[1]) <= seen_radius
                cells = c[near].copy() if near.any() else None
            for b in self.blacklist:
                if cells is not None and b.reached and self._same_place(b, self.goal):
                    b.tries += 1
                    b.until = now
                    b.goals.append(self.goal.goal)
                    b.cells = np.concatenate([b.cells, cells])
                    break
            else:
                self.blacklist.append(Blacklisted([self.goal.goal], now, 1 if cells is not None else self.max_tries,
                                                  cells, self.goal.size_m, 'reached %d times and still there: not '
                                                  'visible from the floor' % self.max_tries if arrived else '',
                                                  reached=True))
        self.goal = None


@dataclass
class Teammate:
    """Another explorer of the team, as it last said (explore's ~team_topic)."""
    name: str
    position: Tuple[float, float]           # [m] global frame
    goal: Optional[Tuple[float, float]]     # its frontier goal, None without one


def share_out(frontiers: List[Frontier], mates: Sequence[Teammate], claim_radius: float = 2.0,
              potential_scale: float = 3.0) -> Tuple[List[Frontier], int]:
    """(this robot's frontiers, best first; how many are left to teammates) for a team exploring
    together.

    A frontier whose goal lies within claim_radius [m] of a teammate's goal is that teammate's. The
    others cost potential_scale times the metres by which this robot's path to them is longer than
    a teammate's straight-line distance: a robot leaves the frontiers nearer to the others, so the
    team spreads out. Two robots that chose the same place keep it for the one whose name sorts
    first (yields_goal)."""
    mine, claimed = [], 0
    for f in frontiers:
        if any(m.goal is not None and math.hypot(f.goal[0] - m.goal[0], f.goal[1] - m.goal[1]) < claim_radius
               for m in mates):
            claimed += 1
            continue
        nearest = min((math.hypot(f.goal[0] - m.position[0], f.goal[1] - m.position[1]) for m in mates),
                      default=math.inf)
        penalty = potential_scale * max(0.0, f.path_m - nearest)
        mine.append(replace(f, cost=f.cost + penalty) if penalty > 0 else f)
    mine.sort(key=lambda f: f.cost)
    return mine, claimed


def yields_goal(goal: Tuple[float, float], me: str, mates: Sequence[Teammate], claim_radius: float = 2.0) -> bool:
    """True if a teammate whose name sorts before `me` heads for a goal within claim_radius of ours."""
    return any(m.goal is not None and m.name < me and math.hypot(goal[0] - m.goal[0], goal[1] - m.goal[1]) < claim_radius
               for m in mates)


@dataclass
class MotionWatch:
    """How long the robot has stood still (moved less than `distance` [m]), whatever its goals."""
    distance: float = 0.2
    anchor: Optional[Tuple[float, float]] = None
    since: float = 0.0

    def update(self, now: float, robot: Tuple[float, float]) -> None:
        if self.anchor is None or math.hypot(robot[0] - self.anchor[0], robot[1] - self.anchor[1]) >= self.distance:
            self.reset(now, robot)

    def reset(self, now: float, robot: Tuple[float, float]) -> None:
        self.anchor, self.since = robot, now

    def still_for(self, now: float) -> float:
        return now - self.since if self.anchor is not None else 0.0


@dataclass
class Plateau:
    """The longest stretch [s] without new explored area while reachable frontiers remained."""
    growth: float = 0.5         # [m^2] of new known area that ends a plateau
    longest: float = 0.0        # [s]
    longest_at: float = 0.0     # [s] when that stretch began
    _mark: Optional[Tuple[float, float]] = None  # (time, known area) at the last growth

    def update(self, now: float, known_m2: float, frontiers_left: bool) -> None:
        if not frontiers_left:
            self._mark = None
            return
        if self._mark is None or known_m2 >= self._mark[1] + self.growth:
            self._mark = (now, known_m2)
            return
        if now - self._mark[0] > self.longest:
            self.longest, self.longest_at = now - self._mark[0], self._mark[0]
