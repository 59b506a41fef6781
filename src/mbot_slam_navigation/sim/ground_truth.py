"""Ground truth of a world for evaluation: where its solids are, and how far map points lie from them.

The world is rasterized once with OpenCV (boxes and circles drawn with sub-pixel precision, grid
shapes resampled), and distances come from OpenCV's Euclidean distance transform of that raster, so
the cost follows the area, not the number of shapes (a 60 x 60 m building of 2,000 boxes takes well
under a second). Which shapes count is the caller's choice: World.blocking(z_lo, z_hi) keeps those
a robot's body meets (a lintel over a door is not a wall).

Frames: the world frame of the world file; a SLAM map is in it when the robot was spawned at the
world origin facing +x, otherwise explore_report moves between the two with the spawn pose.
"""
import math
from typing import Optional, Tuple

import cv2
import numpy as np

from mbot_slam_navigation.maps.map_io import SAVER_OCCUPIED
from mbot_slam_navigation.sim.sdf_world import World, load_world
from mbot_slam_navigation.sim.simulation import GROUND_CLEARANCE
from mbot_slam_navigation.sim.urdf_robot import parse_urdf
from mbot_slam_navigation.sim.xmlutil import XmlError

SURFACE_RESOLUTION = 0.02  # [m] raster of distance_to_surfaces: distances within about 0.015 m
_SHIFT = 8                 # sub-pixel bits of OpenCV's drawing


def as_the_robot_meets_it(world: World, urdf_text: Optional[str], source: str = 'robot_description'
                          ) -> Tuple[World, Optional[str]]:
    """(the world's shapes that a robot of this URDF meets, a warning or None): those overlapping its
    body from GROUND_CLEARANCE to the top of its collision geometry, as the simulator decides. Without
    a URDF, or with one that cannot be read (the warning says why), every shape counts."""
    if not urdf_text:
        return world, None
    try:
        height = parse_urdf(urdf_text, source).height
    except XmlError as e:
        return world, "the robot's height is not known (%s); every shape of the world counts" % e
    return world.blocking(GROUND_CLEARANCE, height), None


def load_truth(world_file: str, map_unknown: str = 'solid', urdf_text: Optional[str] = None,
               source: str = 'robot_description') -> Tuple[Optional[World], Optional[str]]:
    """(the world as a robot of this URDF meets it, a warning or None) for ground-truth figures; (None,
    why) when the world file cannot be read: the figures are then left out, the run's report is not."""
    try:
        world = load_world(world_file, map_unknown)
    except ValueError as e:  # XmlError, MapFileError
        return None, 'no ground truth: %s' % e
    return as_the_robot_meets_it(world, urdf_text, source)


def _extent(world: World, points: Optional[np.ndarray], margin: float) -> Tuple[float, float, float, float]:
    b = world.bounds()
    boxes = [] if b is None else [b]
    if points is not None and len(points):
        boxes.append((points[:, 0].min(), points[:, 1].min(), points[:, 0].max(), points[:, 1].max()))
    if not boxes:
        return -margin, -margin, margin, margin
    a = np.array(boxes)
    return a[:, 0].min() - margin, a[:, 1].min() - margin, a[:, 2].max() + margin, a[:, 3].max() + margin


def draw_solids(world: World, origin: Tuple[float, float], shape: Tuple[int, int], resolution: float,
                outline: bool = True) -> np.ndarray:
    """(rows, cols) uint8 raster, row r / column c the cell [origin + (c, r) * resolution, + resolution):
    1 where a shape covers the cell's centre, and with `outline` also where a shape's boundary passes
    through the cell (so that walls thinner than a cell are not lost)."""
    img = np.zeros(shape, np.uint8)
    scale = float(1 << _SHIFT) / resolution

    def px(points):  # world [m] -> fixed-point pixel coordinates (pixel centres at integers)
        p = (np.asarray(points, float) - origin) / resolution - 0.5
        return np.round(p * (1 << _SHIFT)).astype(np.int32)

    polygons = [px(s.corners()) for s in world.shapes if s.kind == 'box']
    if polygons:
        cv2.fillPoly(img, polygons, 1, lineType=cv2.LINE_8, shift=_SHIFT)
        if outline:
            cv2.polylines(img, polygons, True, 1, 1, cv2.LINE_8, _SHIFT)
    for s in world.shapes:
        if s.kind == 'circle':
            centre = tuple(int(v) for v in px([(s.x, s.y)])[0])
            cv2.circle(img, centre, int(round(s.radius * scale)), 1, -1, cv2.LINE_8, _SHIFT)
        elif s.kind == 'grid':
            # raster pixel (c, r) centre -> the grid's cell: an affine map, sampled at the nearest cell
            c, si = math.cos(s.yaw), math.sin(s.yaw)
            k = resolution / s.resolution
            ox, oy = origin[0] + 0.5 * resolution - s.x, origin[1] + 0.5 * resolution - s.y
            m = np.array([[c * k, si * k, (c * ox + si * oy) / s.resolution - 0.5],
                          [-si * k, c * k, (-si * ox + c * oy) / s.resolution - 0.5]])
            warped = cv2.warpAffine(s.cells.astype(np.uint8), m, (shape[1], shape[0]),
                                    flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP, borderValue=0)
            img |= warped
    return img


def _distance_field(world: World, box: Tuple[float, float, float, float], resolution: float):
    """(field, origin): distance [m] from each cell centre of a raster over `box` to the nearest solid
    (0 in one), OpenCV's exact Euclidean transform of draw_solids; +inf everywhere without solids."""
    x0, y0, x1, y1 = box
    shape = (int(math.ceil((y1 - y0) / resolution)) + 1, int(math.ceil((x1 - x0) / resolution)) + 1)
    solid = draw_solids(world, (x0, y0), shape, resolution)
    if not solid.any():
        return np.full(shape, np.inf, np.float32), (x0, y0)
    # Between a free cell's centre and the nearest solid cell's centre: measured against exact
    # distances to box and circle outlines, this is unbiased (mean error < 1 mm at 0.02 m).
    return cv2.distanceTransform((solid == 0).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * resolution, (x0, y0)


def _sample(field: np.ndarray, origin: Tuple[float, float], resolution: float, pts: np.ndarray) -> np.ndarray:
    """The field interpolated (bilinear) at world points."""
    rows, cols = field.shape
    u = np.clip((pts[:, 0] - origin[0]) / resolution - 0.5, 0, cols - 1)
    v = np.clip((pts[:, 1] - origin[1]) / resolution - 0.5, 0, rows - 1)
    c0, r0 = np.minimum(u.astype(int), cols - 2).clip(0), np.minimum(v.astype(int), rows - 2).clip(0)
    fu, fv = np.clip(u - c0, 0, 1), np.clip(v - r0, 0, 1)
    c1, r1 = np.minimum(c0 + 1, cols - 1), np.minimum(r0 + 1, rows - 1)
    top = field[r0, c0] * (1 - fu) + field[r0, c1] * fu
    bottom = field[r1, c0] * (1 - fu) + field[r1, c1] * fu
    return (top * (1 - fv) + bottom * fv).astype(float)


def distance_to_surfaces(world: World, points: np.ndarray, resolution: float = SURFACE_RESOLUTION) -> np.ndarray:
    """Distance [m] from each (x, y) point to the nearest solid of the world, 0 inside one (+inf for a
    world without shapes); within about 0.8 x resolution of the exact distance (0.016 m at the default)."""
    pts = np.asarray(points, float).reshape(-1, 2)
    if not world.shapes or not len(pts):
        return np.full(len(pts), np.inf)
    field, origin = _distance_field(world, _extent(world, pts, 4 * resolution), resolution)
    if np.isinf(field).all():
        return np.full(len(pts), np.inf)
    return _sample(field, origin, resolution, pts)


def occupied_points(msg, threshold: int = SAVER_OCCUPIED) -> np.ndarray:
    """World positions [m] of the centres of a nav_msgs/OccupancyGrid's occupied cells."""
    data = np.asarray(msg.data, np.int16).reshape(msg.info.height, msg.info.width)
    rows, cols = np.nonzero(data >= threshold)
    res, o = msg.info.resolution, msg.info.origin.position
    return np.column_stack([o.x + (cols + 0.5) * res, o.y + (rows + 0.5) * res])


def rasterize(world: World, resolution: float = 0.05, margin: float = 0.5) -> Tuple[np.ndarray, Tuple[float, float]]:
    """A perfect map of the world: (OccupancyGrid data (rows = y): 100 where a cell's centre lies in a
    box or circle or within half a cell of one (exactly, shape by shape over the cells near it), or in
    a solid cell of a grid shape; 0 elsewhere; origin (x, y) [m] of cell (0, 0)), covering every shape
    plus ``margin``, the origin on a multiple of the resolution."""
    x0, y0, x1, y1 = _extent(world, None, margin)
    x0, y0 = math.floor(x0 / resolution) * resolution, math.floor(y0 / resolution) * resolution
    rows, cols = int(math.ceil((y1 - y0) / resolution)), int(math.ceil((x1 - x0) / resolution))
    out = np.zeros((rows, cols), bool)
    half = 0.5 * resolution
    grids = World(world.name, [s for s in world.shapes if s.kind == 'grid'])
    if grids.shapes:
        out |= draw_solids(grids, (x0, y0), (rows, cols), resolution) > 0
    for s in world.shapes:
        if s.kind == 'grid':
            continue
        corners = s.corners()
        c0 = max(0, int(math.floor((corners[:, 0].min() - half - x0) / resolution)))
        c1 = min(cols, int(math.ceil((corners[:, 0].max() + half - x0) / resolution)) + 1)
        r0 = max(0, int(math.floor((corners[:, 1].min() - half - y0) / resolution)))
        r1 = min(rows, int(math.ceil((corners[:, 1].max() + half - y0) / resolution)) + 1)
        if c0 >= c1 or r0 >= r1:
            continue
        gx, gy = np.meshgrid(x0 + (np.arange(c0, c1) + 0.5) * resolution, y0 + (np.arange(r0, r1) + 0.5) * resolution)
        dx, dy = gx - s.x, gy - s.y
        if s.kind == 'circle':
            hit = np.hypot(dx, dy) <= s.radius + half
        else:
            c, si = math.cos(s.yaw), math.sin(s.yaw)
            u, v = np.abs(c * dx + si * dy), np.abs(-si * dx + c * dy)
            hit = np.hypot(np.maximum(u - s.size_x / 2, 0.0), np.maximum(v - s.size_y / 2, 0.0)) <= half
        out[r0:r1, c0:c1] |= hit
    return np.where(out, 100, 0).astype(np.int8), (x0, y0)
