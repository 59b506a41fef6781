"""Ground truth of a world for evaluation: distances from map points to the true surfaces.

Frames: the world frame of the SDF file; a SLAM map started where the robot was spawned at the
world origin facing +x shares it.
"""
import math
from typing import Tuple

import numpy as np

from mbot_slam_navigation.maps.map_io import SAVER_OCCUPIED
from mbot_slam_navigation.sim.sdf_world import World


def surfaces(world: World) -> Tuple[np.ndarray, np.ndarray]:
    """(segments (N, 4): x1 y1 x2 y2, circles (M, 3): x y r) of every shape's outline."""
    segs, circles = [], []
    for s in world.shapes:
        if s.kind == 'circle':
            circles.append((s.x, s.y, s.radius))
            continue
        c, si = math.cos(s.yaw), math.sin(s.yaw)
        corners = [(s.x + c * a * s.size_x / 2 - si * b * s.size_y / 2, s.y + si * a * s.size_x / 2 + c * b * s.size_y / 2)
                   for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        for k in range(4):
            segs.append(corners[k] + corners[(k + 1) % 4])
    return np.array(segs).reshape(-1, 4), np.array(circles).reshape(-1, 3)


def distance_to_surfaces(world: World, points: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """Distance [m] from each (x, y) point to the nearest surface of the world."""
    segs, circles = surfaces(world)
    pts = np.asarray(points, float).reshape(-1, 2)
    out = np.full(len(pts), np.inf)
    a, b = segs[:, :2], segs[:, 2:]
    ab = b - a
    len2 = np.maximum((ab ** 2).sum(axis=1), 1e-12)
    for i in range(0, len(pts), chunk):
        p = pts[i:i + chunk, None, :]
        t = np.clip(((p - a) * ab).sum(axis=2) / len2, 0.0, 1.0)
        d = np.linalg.norm(p - (a + t[..., None] * ab), axis=2).min(axis=1) if len(segs) else np.inf
        if len(circles):
            dc = np.abs(np.linalg.norm(p - circles[None, :, :2], axis=2) - circles[None, :, 2]).min(axis=1)
            d = np.minimum(d, dc)
        out[i:i + chunk] = d
    return out


def occupied_points(msg, threshold: int = SAVER_OCCUPIED) -> np.ndarray:
    """World positions [m] of the centres of a nav_msgs/OccupancyGrid's occupied cells."""
    data = np.asarray(msg.data, np.int16).reshape(msg.info.height, msg.info.width)
    rows, cols = np.nonzero(data >= threshold)
    res, o = msg.info.resolution, msg.info.origin.position
    return np.column_stack([o.x + (cols + 0.5) * res, o.y + (rows + 0.5) * res])


def rasterize(world: World, resolution: float = 0.05, margin: float = 0.5) -> Tuple[np.ndarray, Tuple[float, float]]:
    """A perfect map of the world: (OccupancyGrid data (rows = y): 100 inside or on a shape, 0 elsewhere,
    origin (x, y) [m] of cell (0, 0)), covering every shape plus ``margin``. A test fixture standing in
    for a saved map where localization is not under test."""
    segs, circles = surfaces(world)
    xs = np.concatenate([segs[:, 0], segs[:, 2], circles[:, 0] - circles[:, 2], circles[:, 0] + circles[:, 2]])
    ys = np.concatenate([segs[:, 1], segs[:, 3], circles[:, 1] - circles[:, 2], circles[:, 1] + circles[:, 2]])
    x0, y0 = math.floor((xs.min() - margin) / resolution) * resolution, math.floor((ys.min() - margin) / resolution) * resolution
    w = int(math.ceil((xs.max() + margin - x0) / resolution))
    h = int(math.ceil((ys.max() + margin - y0) / resolution))
    gx, gy = np.meshgrid(x0 + (np.arange(w) + 0.5) * resolution, y0 + (np.arange(h) + 0.5) * resolution)
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    occupied = distance_to_surfaces(world, pts) <= 0.5 * resolution
    for s in world.shapes:  # cell centres inside a solid
        if s.kind == 'circle':
            occupied |= np.hypot(pts[:, 0] - s.x, pts[:, 1] - s.y) <= s.radius
        else:
            c, si = math.cos(s.yaw), math.sin(s.yaw)
            dx, dy = pts[:, 0] - s.x, pts[:, 1] - s.y
            u, v = c * dx + si * dy, -si * dx + c * dy
            occupied |= (np.abs(u) <= s.size_x / 2) & (np.abs(v) <= s.size_y / 2)
    return np.where(occupied, 100, 0).astype(np.int8).reshape(h, w), (x0, y0)
