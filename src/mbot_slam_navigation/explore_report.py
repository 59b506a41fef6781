"""The exploration report, ROS-free: the map (map_server format), the map with the robot's path and
the frontier goals visited (map.png), explored area against time (area.png) and the figures
(report.json); with the world's ground truth also coverage of the reachable free space and wall
accuracy. The map is scored in the world frame: `world_from_map` (the map frame's pose in the world,
from the spawn pose) moves it there; the identity when SLAM started at the world origin. Metres,
seconds.
"""
import json
import math
import os
from typing import Dict, List, Optional, Sequence, Tuple

import cv2
import numpy as np

from mbot_slam_navigation.home_rooms import room_coverage
from mbot_slam_navigation.map_stats import free_at
from mbot_slam_navigation.maps.map_io import SAVER_FREE, SAVER_OCCUPIED, occupancy_to_image, save_map
from mbot_slam_navigation.nav.frontiers import Grid, inside_polygon
from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, rasterize
from mbot_slam_navigation.sim.sdf_world import World
from mbot_slam_navigation.transforms import compose2d, inverse2d

Pose2D = Tuple[float, float, float]


def map_in_world(m: Grid, world_from_map: Pose2D) -> Grid:
    """The map moved into the world frame by the pose of its frame there: its origin shifted, or for a
    turned frame resampled (nearest cell) into a grid aligned with the world's axes, unknown around."""
    x, y, yaw = world_from_map
    if abs(math.sin(yaw)) < 1e-9 and math.cos(yaw) > 0:
        return Grid(m.data, m.resolution, (m.origin[0] + x, m.origin[1] + y))
    rows, cols = m.data.shape
    corners = np.array([compose2d(world_from_map, (m.origin[0] + a * cols * m.resolution,
                                                   m.origin[1] + b * rows * m.resolution, 0.0))[:2]
                        for a in (0, 1) for b in (0, 1)])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    out_shape = (int(math.ceil((hi[1] - lo[1]) / m.resolution)), int(math.ceil((hi[0] - lo[0]) / m.resolution)))
    # world cell centre -> map frame -> map cell (nearest), as an affine map for OpenCV
    c, s = math.cos(yaw), math.sin(yaw)
    ox, oy = lo[0] + 0.5 * m.resolution - x, lo[1] + 0.5 * m.resolution - y
    a = np.array([[c, s, (c * ox + s * oy - m.origin[0]) / m.resolution - 0.5],
                  [-s, c, (-s * ox + c * oy - m.origin[1]) / m.resolution - 0.5]])
    data = cv2.warpAffine(m.data.astype(np.int16), a, (out_shape[1], out_shape[0]),
                          flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP, borderValue=-1)
    return Grid(data.astype(m.data.dtype), m.resolution, (float(lo[0]), float(lo[1])))


def known_area(m: Grid) -> float:
    """[m^2] of cells the map knows (free or occupied as map_saver counts them)."""
    d = m.data.astype(np.int16)
    return float(np.count_nonzero((d >= 0) & ((d <= SAVER_FREE) | (d >= SAVER_OCCUPIED)))) * m.resolution ** 2


def reachable_free_space(world: World, start: Tuple[float, float], robot_radius: float,
                         resolution: float = 0.05, truth=None,
                         blocked: Optional[np.ndarray] = None) -> Tuple[np.ndarray, Tuple[float, float]]:
    """(mask, origin) of the world's free cells that the robot can sweep: those within robot_radius
    of a centre position reachable from `start` without touching any shape. `truth`: the world's
    rasterize() at this resolution, if the caller has it (it takes a second or two). `blocked` (a
    mask of truth's cells: keep-out zones) counts as shapes, and its cells are never reachable."""
    truth, origin = truth if truth is not None else rasterize(world, resolution)
    free = (truth == 0).astype(np.uint8)
    if blocked is not None:
        free[blocked] = 0
    clearance = cv2.distanceTransform(free, cv2.DIST_L2, 5) * resolution
    centres = (clearance > robot_radius).astype(np.uint8)
    r, c = int((start[1] - origin[1]) / resolution), int((start[0] - origin[0]) / resolution)
    if not centres[r, c]:
        raise ValueError('the start (%.2f, %.2f) is within %.2f m of a shape' % (start[0], start[1], robot_radius))
    n, labels = cv2.connectedComponents(centres, connectivity=8)
    reach = (labels == labels[r, c]).astype(np.uint8)
    k = 2 * int(math.ceil(robot_radius / resolution)) + 1
    swept = cv2.dilate(reach, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
    return (swept > 0) & (free > 0), origin


def keepout_on(truth, resolution: float, keepout: Grid, world_from_map: Pose2D = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Bool mask of the cells of `truth` ((grid, origin), world frame, `resolution` [m]) whose
    centres lie on a forbidden cell (100) of `keepout` (a keep-out mask in the map frame)."""
    grid, origin = truth
    rows, cols = np.indices(grid.shape)
    wx = origin[0] + (cols + 0.5) * resolution
    wy = origin[1] + (rows + 0.5) * resolution
    mx0, my0, myaw = inverse2d(world_from_map)
    c, s = math.cos(myaw), math.sin(myaw)
    mr, mc = keepout.cell_of(mx0 + c * wx - s * wy, my0 + s * wx + c * wy)
    ok = keepout.inside(mr, mc)
    out = np.zeros(grid.shape, bool)
    out[ok] = keepout.data[mr[ok], mc[ok]] >= 100
    return out


def ground_truth_figures(m: Grid, world: World, start: Tuple[float, float], robot_radius: float,
                         wall_tolerance: float = 0.1, truth=None, boundary=None,
                         keepout: Optional[np.ndarray] = None) -> Dict[str, float]:
    """Coverage of the reachable free space and the walls' distance to the world's surfaces; with
    `boundary` ((N, 2) [m], world frame), the reachable space inside it only; `keepout` (a mask of
    truth's cells: keep-out zones) is neither reachable nor passable."""
    truth = truth if truth is not None else rasterize(world, m.resolution)
    mask, origin = reachable_free_space(world, start, robot_radius, m.resolution, truth, keepout)
    if boundary is not None:
        mask = mask & inside_polygon(Grid(mask, m.resolution, origin), boundary)
    rows, cols = np.nonzero(mask)
    x = origin[0] + (cols + 0.5) * m.resolution
    y = origin[1] + (rows + 0.5) * m.resolution
    seen = free_at(m.data, m.resolution, m.origin, x, y, SAVER_FREE)
    orows, ocols = np.nonzero(m.data.astype(np.int16) >= SAVER_OCCUPIED)
    wx, wy = m.centre_of(orows, ocols)
    d = distance_to_surfaces(world, np.column_stack([wx, wy])) if len(wx) else np.zeros(0)
    # A wall cell whose centre lies inside a solid is on the wall, however far from its surface.
    truth, torigin = truth
    tr = np.floor((wy - torigin[1]) / m.resolution).astype(int)
    tc = np.floor((wx - torigin[0]) / m.resolution).astype(int)
    ok = (tr >= 0) & (tc >= 0) & (tr < truth.shape[0]) & (tc < truth.shape[1])
    solid = np.zeros(len(d), bool)
    solid[ok] = truth[tr[ok], tc[ok]] > 0
    d[solid] = 0.0
    return {
        'reachable_free_m2': round(float(len(x)) * m.resolution ** 2, 2),
        'coverage_of_reachable_free': round(float(seen.mean()) if len(seen) else 0.0, 4),
        'wall_cells': int(len(d)),
        'walls_within_tolerance': round(float(np.mean(d <= wall_tolerance)) if len(d) else 0.0, 4),
        'wall_tolerance_m': wall_tolerance,
        'wall_distance_median_m': round(float(np.median(d)), 4) if len(d) else None,
        'wall_distance_max_m': round(float(d.max()), 4) if len(d) else None,
    }


def _map_canvas(m: Grid):
    """(BGR picture of the map about 900 px across, world (x, y) -> pixel, line width)."""
    img = cv2.cvtColor(occupancy_to_image(m.data.astype(np.int16)), cv2.COLOR_GRAY2BGR)
    scale = max(1, 900 // max(img.shape[:2]))
    img = cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    h = m.data.shape[0]

    def px(x, y):
        return (int((x - m.origin[0]) / m.resolution * scale), int((h - (y - m.origin[1]) / m.resolution) * scale))

    return img, px, max(1, scale // 2)


def draw_map(m: Grid, path: Sequence[Tuple[float, float]], goals: Sequence[Tuple[float, float, bool]],
             filename: str) -> None:
    """The map with the driven path (red) and the goals sent (green reached, orange not)."""
    img, px, width = _map_canvas(m)
    if len(path) > 1:
        cv2.polylines(img, [np.array([px(x, y) for x, y in path], np.int32)], False, (0, 0, 220), width)
    for x, y, ok in goals:
        cv2.circle(img, px(x, y), 4 * width, (0, 170, 0) if ok else (0, 140, 255), -1)
    cv2.imwrite(filename, img)


def draw_team_map(m: Grid, paths: Dict[str, Sequence[Tuple[float, float]]], filename: str) -> None:
    """The merged map with each robot's path in its own colour (COLOURS, in name order), a legend,
    and each start marked; written atomically."""
    img, px, width = _map_canvas(m)
    for k, name in enumerate(sorted(paths)):
        colour, path = COLOURS[k % len(COLOURS)], paths[name]
        if len(path) > 1:
            cv2.polylines(img, [np.array([px(x, y) for x, y in path], np.int32)], False, colour, width)
        if path:
            cv2.circle(img, px(*path[0]), 5 * width, colour, 2)
        cv2.putText(img, name, (10, 25 + 22 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.7, colour, 2)
    root, ext = os.path.splitext(filename)
    tmp = root + '.tmp' + ext
    cv2.imwrite(tmp, img)
    os.replace(tmp, filename)


COLOURS = [(200, 80, 0), (0, 0, 220), (0, 150, 0), (180, 0, 180), (0, 140, 255), (120, 120, 0), (80, 80, 80)]


def draw_curves(series: Dict[str, Sequence[Tuple[float, float]]], title: str, filename: str, size=(800, 400),
                marker_x: Optional[float] = None) -> None:
    """Line chart of named (x, y) curves with labelled axes and a legend (OpenCV, written atomically);
    marker_x draws a dotted vertical line there."""
    w, h = size
    img = np.full((h, w, 3), 255, np.uint8)
    left, bottom, top, right = 70, 40, 20, 20
    xs = [p[0] for c in series.values() for p in c] or [0.0]
    ys = [p[1] for c in series.values() for p in c] or [0.0]
    xmax, ymax = max(max(xs), 1.0), max(max(ys), 1.0)
    cv2.line(img, (left, h - bottom), (w - right, h - bottom), (0, 0, 0), 1)
    cv2.line(img, (left, h - bottom), (left, top), (0, 0, 0), 1)
    for i in range(5):
        ty = h - bottom - i * (h - bottom - top) // 4
        cv2.putText(img, '%.0f' % (ymax * i / 4), (5, ty + 4), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 0, 0), 1)
        tx = left + i * (w - left - right) // 4
        cv2.putText(img, '%.0f' % (xmax * i / 4), (tx - 10, h - bottom + 18), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 0, 0), 1)
    cv2.putText(img, title, (left + 10, top + 12), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1)
    to_px = lambda x, y: (left + x / xmax * (w - left - right), h - bottom - y / ymax * (h - bottom - top))  # noqa: E731
    if marker_x is not None and 0 <= marker_x <= xmax:
        mx = int(to_px(marker_x, 0)[0])
        for y0 in range(top, h - bottom, 8):
            cv2.line(img, (mx, y0), (mx, y0 + 3), (120, 120, 120), 1)
    for k, (name, curve) in enumerate(series.items()):
        colour = COLOURS[k % len(COLOURS)]
        pts = np.array([to_px(x, y) for x, y in curve] or [(0.0, 0.0)])
        if len(curve) > 1:
            cv2.polylines(img, [pts.astype(np.int32)], False, colour, 2)
        if len(series) > 1:
            cv2.putText(img, name, (w - right - 190, top + 30 + 16 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1)
    root, ext = os.path.splitext(filename)
    tmp = root + '.tmp' + ext
    cv2.imwrite(tmp, img)
    os.replace(tmp, filename)


def draw_area(curve: Sequence[Tuple[float, float]], filename: str, size=(800, 400)) -> None:
    """Explored area [m^2] against simulated time [s], with labelled axes."""
    draw_curves({'area': curve}, 'explored area [m^2] against simulated time [s]', filename, size)


def _map_figures(report_dir: str, m: Grid, figures: Dict, world: Optional[World], start: Tuple[float, float],
                 robot_radius: float, rooms, world_from_map: Pose2D = (0.0, 0.0, 0.0), boundary=None,
                 keepout: Optional[Grid] = None) -> Dict:
    """`figures` with the map's own (explored area; against the world when given: coverage, walls,
    each room's share), after writing the map (map.pgm, map.yaml) into report_dir. `start` and
    `boundary` (the explored area's polygon, coverage counted inside it) are in the map frame."""
    os.makedirs(report_dir, exist_ok=True)
    figures['explored_area_m2'] = round(known_area(m), 2)
    if world is not None:
        seen = map_in_world(m, world_from_map)
        start_world = compose2d(world_from_map, (start[0], start[1], 0.0))[:2]
        truth = rasterize(world, m.resolution)  # once for all the figures below
        bounds = None if boundary is None else np.array([compose2d(world_from_map, (x, y, 0.0))[:2]
                                                         for x, y in boundary])
        zones = None if keepout is None else keepout_on(truth, m.resolution, keepout, world_from_map)
        figures.update(ground_truth_figures(seen, world, start_world, robot_radius, truth=truth, boundary=bounds,
                                            keepout=zones))
        if rooms:
            figures['room_coverage'] = {k: round(v, 3) for k, v in
                                        room_coverage(seen, truth[0], truth[1], m.resolution, rooms=rooms).items()}
    save_map(os.path.join(report_dir, 'map'), m.data, m.resolution, (m.origin[0], m.origin[1], 0.0))
    return figures


def write_report(report_dir: str, m: Grid, path: List[Tuple[float, float]], goals: List[Tuple[float, float, bool]],
                 curve: List[Tuple[float, float]], figures: Dict, world: Optional[World] = None,
                 start: Tuple[float, float] = (0.0, 0.0), robot_radius: float = 0.2, rooms=(),
                 world_from_map: Pose2D = (0.0, 0.0, 0.0), boundary=None, keepout: Optional[Grid] = None) -> Dict:
    """Writes map.pgm/map.yaml, map.png, area.png and report.json into report_dir; returns the figures.
    With `rooms` (home_rooms.Room) and the world, also the share of each room's floor mapped free.
    `world` holds the shapes that count (World.blocking for the robot's heights); the map, path,
    start and `boundary` (an explored area's polygon: coverage counts inside it) are in the map
    frame, whose pose in the world is `world_from_map`. `keepout` (a keep-out filter's mask, map
    frame) is left out of the reachable space."""
    figures = _map_figures(report_dir, m, dict(figures), world, start, robot_radius, rooms, world_from_map, boundary,
                           keepout)
    draw_map(m, path, goals, os.path.join(report_dir, 'map.png'))
    draw_area(curve, os.path.join(report_dir, 'area.png'))
    write_figures(report_dir, figures)
    return figures


def write_figures(report_dir: str, figures: Dict) -> None:
    """report.json, written atomically (a reader never sees half a file)."""
    os.makedirs(report_dir, exist_ok=True)
    tmp = os.path.join(report_dir, '.report.json.tmp')
    with open(tmp, 'w') as f:
        json.dump(figures, f, indent=2)
    os.replace(tmp, os.path.join(report_dir, 'report.json'))


def team_figures(reports: Dict[str, Dict]) -> Dict:
    """The team's figures from each robot's explorer report (by robot name): outcome `complete` only
    if every robot's is, robots `lost` aside (the base station stopped hearing from them; the team
    finished without them, and `robots_lost` names them), else the first of error, stuck, timeout,
    not_started found (`lost` when every robot is); the exploration time is the last robot's;
    distances, goals and collisions per robot and summed."""
    lost = sorted(name for name, r in reports.items() if r.get('outcome') == 'lost')
    outcomes = [r.get('outcome', 'not_started') for r in reports.values() if r.get('outcome') != 'lost']
    outcome = 'complete' if outcomes and all(o == 'complete' for o in outcomes) else next(
        (o for o in ('error', 'stuck', 'timeout', 'not_started') if o in outcomes), 'lost' if lost else 'not_started')
    per_robot = {name: {k: r.get(k) for k in ('outcome', 'exploration_time_s', 'distance_m', 'goals_sent',
                                              'goals_failed', 'collisions', 'why') if k in r or k != 'why'}
                 for name, r in sorted(reports.items())}
    total = lambda key: round(sum(float(r.get(key) or 0) for r in reports.values()), 2)  # noqa: E731
    return {
        'outcome': outcome,
        'robots': len(reports),
        'exploration_time_s': max((float(r.get('exploration_time_s') or 0) for r in reports.values()), default=0.0),
        'total_time_s': max((float(r.get('total_time_s') or 0) for r in reports.values()), default=0.0),
        'wall_time_s': max((float(r.get('wall_time_s') or 0) for r in reports.values()), default=0.0),
        'distance_m': total('distance_m'),
        'goals_sent': int(total('goals_sent')),
        'goals_failed': int(total('goals_failed')),
        'collisions': int(total('collisions')),
        'per_robot': per_robot,
        'given_up': [g for r in reports.values() for g in r.get('given_up', [])],
        'robots_lost': lost,
    }


def write_team_report(report_dir: str, m: Grid, paths: Dict[str, List[Tuple[float, float]]],
                      curve: List[Tuple[float, float]], reports: Dict[str, Dict], world: Optional[World] = None,
                      start: Tuple[float, float] = (0.0, 0.0), robot_radius: float = 0.2, rooms=(),
                      extra: Optional[Dict] = None) -> Dict:
    """The team's report in report_dir: the merged map (map.pgm/map.yaml), map.png with each robot's
    path in its own colour, area.png (the merged map's known area against time) and report.json
    (team_figures and `extra`, with the merged map scored against the world when given); returns the
    figures."""
    figures = _map_figures(report_dir, m, dict(team_figures(reports), **(extra or {})), world, start, robot_radius,
                           rooms)
    draw_team_map(m, paths, os.path.join(report_dir, 'map.png'))
    draw_area(curve, os.path.join(report_dir, 'area.png'))
    write_figures(report_dir, figures)
    return figures
