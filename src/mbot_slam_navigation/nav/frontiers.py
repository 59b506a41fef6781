"""Frontier search, ROS-free: where the map ends, which of those places the robot can reach, and
what each costs (rank_frontiers). The tour through them is nav/tour.py, the explorer's decisions
between cycles nav/explore_state.py, a team's sharing nav/team.py; the node is nav/explore.py.

Grids are nav_msgs/OccupancyGrid-like: `data` (rows = y from the origin up, cols = x), -1 unknown,
0..100 occupancy; `origin` is the world corner [m] of cell (0, 0); everything in the map frame.

A frontier cell is a known cell that is not occupied (any value from 0 up to `occupied_min`, so
probabilistic maps work too) with an unknown 4-neighbour. Frontier cells group 8-connected; a group
shorter than `min_frontier_size` [m] (cells x resolution, as explore_lite measures it) is ignored.
The goal of a frontier is its cell nearest to the robot by path on the global costmap (cells below
the inscribed cost, known), never its centroid, which may lie inside a wall.
"""
import bisect
import math
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

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
CURRENT_RADIUS = 1.0  # [m] a frontier with a cell this near the goal being driven to is that goal's
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
    data = m.data
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


def inside_polygon(m: Grid, polygon) -> np.ndarray:
    """Bool mask of the cells of m whose centres lie inside `polygon` ((N, 2) [m], map frame)."""
    pts = (np.asarray(polygon, float) - np.asarray(m.origin)) / m.resolution - 0.5
    mask = np.zeros(m.data.shape, np.uint8)
    # OpenCV draws at integer vertices: 4 bits of sub-cell precision
    cv2.fillPoly(mask, [np.rint(pts * 16).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=4)
    return mask > 0


def keepout_cells(mask: Grid, m: Grid) -> np.ndarray:
    """Bool mask of the cells of m whose centres lie on a keep-out cell of `mask` (a costmap
    filter's mask: OccupancyGrid values, 100 forbidden; any origin and resolution, same frame)."""
    h, w = m.data.shape
    mc, mr = mask.cell_of(m.centre_of(0, np.arange(w))[0], 0)[1], mask.cell_of(0, m.centre_of(np.arange(h), 0)[1])[0]
    ok_r = (mr >= 0) & (mr < mask.data.shape[0])
    ok_c = (mc >= 0) & (mc < mask.data.shape[1])
    out = np.zeros((h, w), bool)
    if ok_r.any() and ok_c.any():
        out[np.ix_(ok_r, ok_c)] = mask.data[np.ix_(mr[ok_r], mc[ok_c])] >= 100
    return out


def _frontier_groups(m: Grid, unknown: np.ndarray, occupied_min: int, min_cells: int = 1,
                     inside: Optional[np.ndarray] = None, stats: Optional[dict] = None,
                     excluded: Optional[np.ndarray] = None) -> List[np.ndarray]:
    """The frontiers of at least min_cells cells, largest first (a large map has thousands of
    one- and two-cell fragments: they are counted, not listed). With `inside` (a mask of m), only
    its cells count; stats['outside_m'] gets the frontier [m] left out. Cells of `excluded` (keep-out
    zones) are never frontier cells."""
    data = m.data
    open_known = (data >= 0) & (data < occupied_min)
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    frontier = (open_known & (cv2.dilate(unknown, cross) > 0)).astype(np.uint8)
    if excluded is not None:
        frontier &= ~excluded
    if inside is not None:
        if stats is not None:
            stats['outside_m'] = float(np.count_nonzero(frontier & ~inside)) * m.resolution
        frontier &= inside.astype(np.uint8)
    n, labels, areas, _ = cv2.connectedComponentsWithStats(frontier, connectivity=8)
    # one pass over the labelled cells, split by label (not one scan of the grid per group)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    if min_cells > 1:
        big = areas[lab, cv2.CC_STAT_AREA] >= min_cells
        rows, cols, lab = rows[big], cols[big], lab[big]
    order = np.argsort(lab, kind='stable')
    rows, cols, lab = rows[order], cols[order], lab[order]
    splits = np.flatnonzero(np.diff(lab)) + 1
    groups = [np.column_stack([r, c]) for r, c in zip(np.split(rows, splits), np.split(cols, splits)) if len(r)]
    return sorted(groups, key=len, reverse=True)


def passable(costmap: Grid, m: Grid, occupied_min: int = SAVER_OCCUPIED) -> np.ndarray:
    """Costmap cells the robot's centre may cross: cost below inscribed, and known and not occupied
    in the map (the costmap may count unknown space as free)."""
    cost = costmap.data
    ok = (cost >= 0) & (cost < COST_INSCRIBED)
    if (m.data.shape == cost.shape and m.resolution == costmap.resolution
            and np.allclose(m.origin, costmap.origin, atol=1e-6 * m.resolution)):
        v = m.data  # the usual case: the global costmap is laid on the map
        return ok & (v >= 0) & (v < occupied_min)
    rows, cols = np.indices(cost.shape)
    x, y = costmap.centre_of(rows, cols)
    mr, mc = m.cell_of(x, y)
    inside = m.inside(mr, mc)
    known_open = np.zeros_like(ok)
    v = m.data[mr[inside], mc[inside]].astype(np.int16)
    known_open[inside] = (v >= 0) & (v < occupied_min)
    return ok & known_open


def _crop(g: Grid, r0: int, c0: int, r1: int, c1: int) -> Grid:
    return Grid(g.data[r0:r1, c0:c1], g.resolution,
                (g.origin[0] + c0 * g.resolution, g.origin[1] + r0 * g.resolution))


def _around_known(m: Grid, costmap: Grid, robot: Tuple[float, float], margin: int) -> Tuple[Grid, Grid]:
    """(m, costmap) cut to the known cells of m and the robot's cell, grown by `margin` cells (and
    by one more, so that every unknown cell beyond the cut is unknown space reaching the cut's edge,
    as it reaches the map's edge beyond). A SLAM map is allocated larger than what is known (at the
    start of a large building, many times larger): the search runs over the part that can hold a
    frontier. The costmap is cut with the map when it is laid on it (the usual case), else kept."""
    known = m.data >= 0
    rows, cols = np.flatnonzero(known.any(axis=1)), np.flatnonzero(known.any(axis=0))
    if not len(rows):
        return m, costmap
    rr, rc = m.cell_of(robot[0], robot[1])
    r0, r1 = min(int(rows[0]), int(rr)) - margin - 1, max(int(rows[-1]), int(rr)) + margin + 2
    c0, c1 = min(int(cols[0]), int(rc)) - margin - 1, max(int(cols[-1]), int(rc)) + margin + 2
    h, w = m.data.shape
    # at multiples of 4 cells: tour_order's blocks of 1, 2 or 4 cells stay those of the whole map
    r0, c0, r1, c1 = max(r0 // 4 * 4, 0), max(c0 // 4 * 4, 0), min(r1, h), min(c1, w)
    if (r0, c0, r1, c1) == (0, 0, h, w):
        return m, costmap
    same = (costmap.data.shape == m.data.shape and costmap.resolution == m.resolution
            and np.allclose(m.origin, costmap.origin, atol=1e-6 * m.resolution))
    return _crop(m, r0, c0, r1, c1), _crop(costmap, r0, c0, r1, c1) if same else costmap


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
                   min_unknown_beside: float = 0.0, gain_size_max: float = 0.0, enough: int = 0,
                   eligible: Optional[Callable[[Frontier], bool]] = None,
                   boundary: Optional[np.ndarray] = None, keepout: Optional[Grid] = None) -> List[Frontier]:
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

    With `boundary` ((N, 2) [m], map frame: frontier_exploration's polygon) only the frontier cells
    inside it count; stats['outside_m'] says how much frontier it left out. With `keepout` (a keep-out
    filter's mask, map frame) neither its cells nor the unknown space in it make frontiers;
    stats['keepout_m'] says how much frontier that took away.

    A frontier's size counts in its cost up to gain_size_max [m] (0: no cap). Uncapped, the edge of
    the laser's view down a corridor (60 m of frontier in the office, seen from its lobby) outweighs
    20 m of path, and the lobby behind the robot was left for last: 13-19 m back across the floor at
    the end, plateaus of 67 and 113 s.
    """
    g_reach = int(math.ceil(GAIN_RADIUS / m.resolution))
    k = 2 * int(math.ceil(goal_reach / costmap.resolution)) + 1  # the window of cells within goal_reach
    m, costmap = _around_known(m, costmap, robot, g_reach + k + 2)
    if stats is not None:
        stats['costmap'] = costmap  # the part of it searched (stats['passable']'s grid)
    rr, rc = costmap.cell_of(robot[0], robot[1])
    if not costmap.inside(rr, rc):
        if stats is not None:
            stats['robot_outside'] = True  # the costmap has not grown to the robot yet
        return []
    open_cells = passable(costmap, m, occupied_min)
    cost = costmap.data
    # Within escape_radius of the robot, any cell short of lethal is passable: a robot that stands
    # in the inscribed zone (an obstacle appeared beside it) can still back out, as move_base does.
    e = int(math.ceil(escape_radius / costmap.resolution))
    er0, ec0 = max(int(rr) - e, 0), max(int(rc) - e, 0)
    rows, cols = np.ogrid[er0:int(rr) + e + 1, ec0:int(rc) + e + 1]
    near = cost[er0:int(rr) + e + 1, ec0:int(rc) + e + 1]
    around = ((rows - rr) ** 2 + (cols - rc) ** 2 <= (escape_radius / costmap.resolution) ** 2) & (near >= 0) & (near < 100)
    open_cells[er0:er0 + around.shape[0], ec0:ec0 + around.shape[1]] |= around
    dist = _core._path_lengths(open_cells.view(np.uint8), int(rc), int(rr))
    if stats is not None:
        stats['reachable_m2'] = float(np.count_nonzero(dist >= 0)) * costmap.resolution ** 2
        stats['passable'] = open_cells  # for tour_order
    blocked = None
    avoid_goals = np.asarray(avoid_goals, float).reshape(-1, 2)
    if len(avoid_goals):
        blocked = np.zeros(cost.shape, np.uint8)
        r = max(1, int(round(avoid_radius / costmap.resolution)))
        for gx, gy in avoid_goals:
            br, bc = costmap.cell_of(gx, gy)
            cv2.circle(blocked, (int(bc), int(br)), r, 1, -1)

    def reach_and_goal_ok(r0: int, c0: int, r1: int, c1: int) -> Tuple[np.ndarray, np.ndarray]:
        """In the window [r0, r1) x [c0, c1): the cells the robot can reach clear of the inflated
        zone (cost below goal_cost_max), and those of them that may be goals (not near avoid_goals)."""
        reach_ok = (dist[r0:r1, c0:c1] >= 0) & open_cells[r0:r1, c0:c1] & (cost[r0:r1, c0:c1] < goal_cost_max)
        return reach_ok, reach_ok if blocked is None else reach_ok & (blocked[r0:r1, c0:c1] == 0)
    avoid = np.asarray(avoid, float).reshape(-1, 2)
    kr, kc = costmap.cell_of(*keep_goal) if keep_goal is not None else (-1, -1)
    unknown = unknown_space(m, occupied_min, min_unknown_area)
    # beyond the grid's edge is unknown too (the SLAM map grows as the robot sees more)
    unknown_beyond = cv2.copyMakeBorder(unknown, g_reach, g_reach, g_reach, g_reach, cv2.BORDER_CONSTANT, value=1)
    inside = inside_polygon(m, boundary) if boundary is not None else None
    zone = keepout_cells(keepout, m) if keepout is not None else None
    if zone is not None and zone.any():
        if stats is not None:
            # what the zone takes away: frontier cells in it, and those whose unknown lies in it only
            open_known = (m.data >= 0) & (m.data < occupied_min)
            cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
            before = open_known & (cv2.dilate(unknown, cross) > 0)
            after = open_known & (cv2.dilate(unknown & ~zone, cross) > 0) & ~zone
            stats['keepout_m'] = float(np.count_nonzero(before & ~after)) * m.resolution
        unknown = unknown & ~zone
        unknown_beyond = cv2.copyMakeBorder(unknown, g_reach, g_reach, g_reach, g_reach, cv2.BORDER_CONSTANT, value=1)
    elif stats is not None:
        stats['keepout_m'] = 0.0
    groups = [g for g in _frontier_groups(m, unknown, occupied_min,
                                          max(1, int(math.ceil(min_frontier_size / m.resolution - 1e-9))),
                                          inside, stats, excluded=zone)
              if len(g) * m.resolution >= min_frontier_size]

    def evaluate(g: np.ndarray) -> Optional[Frontier]:
        """The frontier of group g ((N, 2) rows, cols), or None (appended to `unreachable`)."""
        x, y = m.centre_of(g[:, 0], g[:, 1])
        if len(avoid):
            keep = np.min(np.hypot(x[:, None] - avoid[None, :, 0], y[:, None] - avoid[None, :, 1]), axis=1) >= avoid_radius
            if keep.sum() * m.resolution < min_frontier_size:
                if unreachable is not None:
                    unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), len(x) * m.resolution,
                                               'too little of it (%.2f m) lies farther than %.1f m from places '
                                               'visited or given up' % (keep.sum() * m.resolution, avoid_radius)))
                return None
            x, y, g = x[keep], y[keep], g[keep]
        # the unknown space it borders, within GAIN_RADIUS of its cells (in a window around it;
        # unknown_beyond's cell (r + g_reach, c + g_reach) is the map's (r, c))
        ur0, uc0 = int(g[:, 0].min()), int(g[:, 1].min())
        ur1, uc1 = int(g[:, 0].max()) + 2 * g_reach + 1, int(g[:, 1].max()) + 2 * g_reach + 1
        others = np.ones((ur1 - ur0, uc1 - uc0), np.uint8)  # 0 on its cells: distances from them
        others[g[:, 0] - ur0 + g_reach, g[:, 1] - uc0 + g_reach] = 0
        within = cv2.distanceTransform(others, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) <= g_reach
        unknown_m2 = float(np.count_nonzero(within & (unknown_beyond[ur0:ur1, uc0:uc1] > 0))) * m.resolution ** 2
        size = len(x) * m.resolution
        if unknown_m2 < min_unknown_beside:
            # a sliver the laser grazed: a trip there shows next to nothing (measured: the office's
            # end game turned back 26 s into a 19 m trip for 0.1 m^2, and the trip took 70 s more)
            if unreachable is not None:
                unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), size,
                                           'only %.2f m^2 unknown within %.1f m of it (min_unknown_beside %.2f m^2)'
                                           % (unknown_m2, GAIN_RADIUS, min_unknown_beside)))
            return None
        cr, cc = costmap.cell_of(x, y)
        inside = costmap.inside(cr, cc)
        # the cells within goal_reach of the frontier, in a window around it (not the whole grid)
        half = k // 2
        r0, c0 = max(int(cr.min()) - half, 0), max(int(cc.min()) - half, 0)
        r1, c1 = min(int(cr.max()) + half + 1, cost.shape[0]), min(int(cc.max()) + half + 1, cost.shape[1])
        candidates = reachable = np.zeros((max(r1 - r0, 0), max(c1 - c0, 0)), bool)
        if inside.any() and candidates.size:
            far = np.ones(candidates.shape, np.uint8)  # 0 on the frontier's cells
            far[cr[inside] - r0, cc[inside] - c0] = 0
            near = cv2.distanceTransform(far, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) <= half
            reach_ok, goal_ok = reach_and_goal_ok(r0, c0, r1, c1)
            reachable, candidates = near & reach_ok, near & goal_ok
        if not candidates.any():
            if unreachable is not None:
                why = ('its only goals lie within %.1f m of goals that failed or where the robot stood with it '
                       'still there' % avoid_radius if reachable.any() else
                       'unreachable: no cell within %.1f m of it that the robot can reach clear of obstacles on the '
                       'global costmap' % goal_reach)
                unreachable.append(GivenUp(float(np.mean(x)), float(np.mean(y)), size, why))
            return None
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
                return None
        gx, gy = costmap.centre_of(gr, gc)
        path_m = float(d[gr - r0, gc - c0]) * costmap.resolution
        gain = min(size, gain_size_max) if gain_size_max > 0 else size
        return Frontier(np.column_stack([x, y]), size, (float(gx), float(gy)), path_m,
                        potential_scale * path_m - gain_scale * gain, unknown_m2)

    out = []
    # In the order of a lower bound of their cost (the straight line to their nearest cell, less
    # goal_reach, and their whole size), the frontiers near keep_goal first (ExploreState.choose
    # looks for the one being explored there): with `enough`, the ranking stops when that many
    # frontiers taken by `eligible` are ranked and no frontier left can cost less than the
    # enough-th of them. Ranking a frontier takes 0.3-1 ms; a large building has a hundred, of
    # which the explorer can use the best tour_frontiers.
    lower = np.zeros(len(groups))
    first = np.zeros(len(groups), bool)
    if potential_scale < 0 or gain_scale < 0:
        enough = 0  # no lower bound then
    if enough > 0:
        for i, g in enumerate(groups):
            x, y = m.centre_of(g[:, 0], g[:, 1])
            gain = len(g) * m.resolution
            gain = min(gain, gain_size_max) if gain_size_max > 0 else gain
            lower[i] = potential_scale * max(0.0, float(np.min(np.hypot(x - robot[0], y - robot[1]))) - goal_reach) \
                - gain_scale * gain
            if keep_goal is not None:
                first[i] = np.min(np.hypot(x - keep_goal[0], y - keep_goal[1])) < CURRENT_RADIUS
    order = sorted(range(len(groups)), key=lambda i: (not first[i], lower[i]))
    taken: List[float] = []  # costs of the eligible frontiers ranked, ascending
    unranked = []
    for n, i in enumerate(order):
        if enough > 0 and not first[i] and len(taken) >= enough and lower[i] > taken[enough - 1]:
            unranked = [groups[j] for j in order[n:]]
            break
        f = evaluate(groups[i])
        if f is not None:
            out.append((f.cost, i, f))  # equal costs: the larger first, however they were ranked
            if eligible is None or eligible(f):
                bisect.insort(taken, f.cost)
    if stats is not None:
        stats['unranked'] = [np.column_stack(m.centre_of(g[:, 0], g[:, 1])) for g in unranked]
    return [f for _, _, f in sorted(out, key=lambda e: e[:2])]
