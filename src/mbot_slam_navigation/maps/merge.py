"""Merging several robots' occupancy grids into one (multirobot_map_merge's job), ROS-free.

A robot's grid lies in its own map frame; `Pose2` (x [m], y [m], yaw [rad]) is that frame's pose in
the merged (world) frame: the robot's initial pose when it is known, else estimated by matching the
grids (estimate_pose). Grids are nav_msgs/OccupancyGrid data: rows along y, -1 unknown, 0..100, the
grid's own origin (x, y) [m] in its map frame with yaw 0 (what slam_gmapping publishes).

Merging takes, cell by cell, the highest value any robot knows (unknown loses, occupied wins), as
multirobot_map_merge composes its grids: a wall one robot has seen is never erased by another that
saw the same place from elsewhere. OpenCV does the warping (nearest cell) and the feature matching
(ORB and a RANSAC fit of a rotation and translation, as multirobot_map_merge does).
"""
import math
from typing import List, Optional, Sequence, Tuple

import cv2
import numpy as np

from mbot_slam_navigation.maps.map_io import SAVER_OCCUPIED
from mbot_slam_navigation.nav.frontiers import Grid

Pose2 = Tuple[float, float, float]


def _corners(g: Grid, pose: Pose2) -> np.ndarray:
    h, w = g.data.shape
    pts = np.array([[g.origin[0], g.origin[1]], [g.origin[0] + w * g.resolution, g.origin[1]],
                    [g.origin[0], g.origin[1] + h * g.resolution],
                    [g.origin[0] + w * g.resolution, g.origin[1] + h * g.resolution]])
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.column_stack([pose[0] + c * pts[:, 0] - s * pts[:, 1], pose[1] + s * pts[:, 0] + c * pts[:, 1]])


def merge(grids: Sequence[Tuple[Grid, Pose2]], resolution: Optional[float] = None,
          trails: Optional[Sequence[Sequence[Tuple[float, float]]]] = None, trust_margin: float = 0.5) -> Grid:
    """One grid in the merged frame covering every (grid, pose of its map frame) given; each cell the
    highest value of the robots' cells whose centres fall in it (-1 where none knows it).

    With `trails` (each robot's driven path, world (x, y), in the order of `grids`), a robot's
    occupied cells count only where it is, within trust_margin [m], the nearest of the robots that
    know the cell: a SLAM map is most exact near where its robot drove, and two robots' small
    disagreements would otherwise thicken every wall both saw (one robot's far wall 0.1 m off
    doubled the home's west wall)."""
    if not grids:
        raise ValueError('merge: no grids')
    res = resolution or min(g.resolution for g, _ in grids)
    corners = np.vstack([_corners(g, p) for g, p in grids])
    x0, y0 = math.floor(corners[:, 0].min() / res) * res, math.floor(corners[:, 1].min() / res) * res
    w = int(math.ceil((corners[:, 0].max() - x0) / res - 1e-9))
    h = int(math.ceil((corners[:, 1].max() - y0) / res - 1e-9))
    placed = []
    for g, pose in grids:
        c, s = math.cos(pose[2]), math.sin(pose[2])
        k = g.resolution / res
        # source pixel (col, row) -> merged pixel: pixel centres at integer coordinates (OpenCV's)
        cx = g.origin[0] + 0.5 * g.resolution
        cy = g.origin[1] + 0.5 * g.resolution
        bx = (pose[0] + c * cx - s * cy - x0) / res - 0.5
        by = (pose[1] + s * cx + c * cy - y0) / res - 0.5
        m = np.array([[c * k, -s * k, bx], [s * k, c * k, by]])
        placed.append(cv2.warpAffine(g.data.astype(np.int16), m, (w, h), flags=cv2.INTER_NEAREST,
                                     borderMode=cv2.BORDER_CONSTANT, borderValue=-1))
    out = np.full((h, w), -1, np.int16)
    for warped in placed:
        np.maximum(out, warped, out=out)
    if trails is not None and len(placed) > 1 and all(len(t) for t in trails):
        far = []
        for warped, trail in zip(placed, trails):
            mask = np.full((h, w), 255, np.uint8)
            px = _trail_pixels(trail, (x0, y0), res)
            cv2.polylines(mask, [px], False, 0, 1)
            mask[np.clip(px[:, 1], 0, h - 1), np.clip(px[:, 0], 0, w - 1)] = 0  # a trail of one point
            d = cv2.distanceTransform(mask, cv2.DIST_L2, 5) * res
            far.append(np.where(warped >= 0, d, np.inf))
        nearest = np.min(far, axis=0)
        trusted = np.full((h, w), -1, np.int16)
        for warped, d in zip(placed, far):
            np.maximum(trusted, np.where(d <= nearest + trust_margin, warped, -1), out=trusted)
        # occupied only where a trusted robot says so (the nearest robot knows every known cell, so
        # `trusted` is known wherever `out` is)
        out = np.where((out >= SAVER_OCCUPIED) & (trusted < SAVER_OCCUPIED), trusted, out)
    return Grid(out.astype(np.int8), res, (x0, y0))


UPSAMPLE = 2  # ORB finds too few corners on 5 cm walls one cell thick; at 2.5 cm, blurred, enough


def _image(g: Grid) -> np.ndarray:
    """8-bit picture of the grid for feature matching (walls black, free white, unknown grey),
    upsampled and blurred."""
    d = g.data.astype(np.int16)
    img = np.full(d.shape, 128, np.uint8)
    img[(d >= 0) & (d < 50)] = 255
    img[d >= SAVER_OCCUPIED] = 0
    img = cv2.resize(img, None, fx=UPSAMPLE, fy=UPSAMPLE, interpolation=cv2.INTER_NEAREST)
    return cv2.GaussianBlur(img, (3, 3), 0)


def estimate_pose(a: Grid, b: Grid, min_inliers: int = 20) -> Tuple[Optional[Pose2], str]:
    """(pose of b's map frame in a's map frame, '') from the grids' overlap, or (None, why): too few
    features, too few matches agreeing on one rotation and translation (fewer than min_inliers),
    or a fit that scales (the grids do not show the same place)."""
    if abs(a.resolution - b.resolution) > 1e-9:
        return None, 'the grids have different resolutions (%.3f and %.3f m)' % (a.resolution, b.resolution)
    orb = cv2.ORB_create(nfeatures=3000)
    ka, da = orb.detectAndCompute(_image(a), None)
    kb, db = orb.detectAndCompute(_image(b), None)
    if da is None or db is None or len(ka) < min_inliers or len(kb) < min_inliers:
        return None, 'too few features (%d and %d) to match' % (len(ka or ()), len(kb or ()))
    # Lowe's ratio test: a match only where the best is clearly better than the second best
    pairs = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(db, da, k=2)
    matches = [p[0] for p in pairs if len(p) == 2 and p[0].distance < 0.8 * p[1].distance]
    if len(matches) < min_inliers:
        return None, 'too few matching features (%d, at least %d needed)' % (len(matches), min_inliers)
    # image pixel centre i + 0.5 covers grid cell i // UPSAMPLE, whose centre is at grid pixel i // UPSAMPLE
    pb = (np.float32([kb[m.queryIdx].pt for m in matches]) + 0.5) / UPSAMPLE - 0.5
    pa = (np.float32([ka[m.trainIdx].pt for m in matches]) + 0.5) / UPSAMPLE - 0.5
    cv2.setRNGSeed(1)  # RANSAC: the same grids give the same answer
    m, inliers = cv2.estimateAffinePartial2D(pb, pa, method=cv2.RANSAC, ransacReprojThreshold=1.0, maxIters=5000,
                                             confidence=0.999)
    n = int(inliers.sum()) if inliers is not None else 0
    if m is None or n < min_inliers:
        return None, 'the overlap is too small: %d features agree on one placement, at least %d needed' % (n, min_inliers)
    scale = math.hypot(m[0, 0], m[1, 0])
    if abs(scale - 1.0) > 0.05:
        return None, 'the best fit scales the map by %.2f: the grids do not show the same place' % scale
    yaw = math.atan2(m[1, 0], m[0, 0])
    c, s = math.cos(yaw), math.sin(yaw)
    # pixel (col, row) centre of cell (col, row) is at origin + (col + 0.5, row + 0.5) * res
    res = a.resolution
    t = m[:, 2]
    ox = a.origin[0] + res * (t[0] + 0.5 - (c * 0.5 - s * 0.5)) - (c * b.origin[0] - s * b.origin[1])
    oy = a.origin[1] + res * (t[1] + 0.5 - (s * 0.5 + c * 0.5)) - (s * b.origin[0] + c * b.origin[1])
    return (float(ox), float(oy), float(yaw)), ''



def _trail_pixels(trail: Sequence[Tuple[float, float]], origin: Tuple[float, float], res: float) -> np.ndarray:
    """A driven path (world (x, y) points) as the int32 pixel (column, row) of a grid with that origin
    and resolution, for OpenCV's drawing."""
    return np.round(np.array([[(x - origin[0]) / res - 0.5, (y - origin[1]) / res - 0.5] for x, y in trail])).astype(np.int32)


def clear_swept(m: Grid, trails: Sequence[Sequence[Tuple[float, float]]], radius: float) -> Grid:
    """m with its occupied cells (>= SAVER_OCCUPIED) within `radius` [m] of a robot's trail (world (x, y) points
    in the order driven) made free: the robots' bodies stood there, so whatever a robot's laser saw
    there was a teammate, not a wall (a SLAM map keeps a teammate it saw standing in a doorway as an
    obstacle, which would close that door to the whole team). Unknown cells stay unknown."""
    if radius <= 0 or not any(len(t) for t in trails):
        return m
    mask = np.zeros(m.data.shape, np.uint8)
    r = max(1, int(round(radius / m.resolution)))
    for trail in trails:
        if not len(trail):
            continue
        px = _trail_pixels(trail, m.origin, m.resolution)
        if len(px) > 1:
            cv2.polylines(mask, [px], False, 1, thickness=2 * r + 1)
        for p in px:
            cv2.circle(mask, (int(p[0]), int(p[1])), r, 1, -1)
    data = m.data.copy()
    data[(mask > 0) & (data >= SAVER_OCCUPIED)] = 0
    return Grid(data, m.resolution, m.origin)


def padded_to_blocks(m: Grid, block: float, cover: Optional[Grid] = None) -> Grid:
    """`m` grown with unknown cells to whole blocks of `block` [m] aligned on the world origin, so that
    its size and origin change only when the explored part crosses a block's edge; and to cover
    `cover` (the map last sent, same resolution) too, so that a map whose edge goes back and forth
    across a block's edge keeps its size."""
    n = max(1, int(round(block / m.resolution)))
    c0 = int(np.floor(m.origin[0] / m.resolution + 1e-6))
    r0 = int(np.floor(m.origin[1] / m.resolution + 1e-6))
    h, w = m.data.shape
    lo_c, lo_r = (c0 // n) * n, (r0 // n) * n
    hi_c, hi_r = -((-(c0 + w)) // n) * n, -((-(r0 + h)) // n) * n
    if cover is not None:
        cc = int(np.floor(cover.origin[0] / cover.resolution + 1e-6))
        cr = int(np.floor(cover.origin[1] / cover.resolution + 1e-6))
        lo_c, lo_r = min(lo_c, cc), min(lo_r, cr)
        hi_c, hi_r = max(hi_c, cc + cover.data.shape[1]), max(hi_r, cr + cover.data.shape[0])
    left, bottom = c0 - lo_c, r0 - lo_r
    data = np.pad(m.data, ((bottom, hi_r - r0 - h), (left, hi_c - c0 - w)), constant_values=-1)
    origin = (m.origin[0] - left * m.resolution, m.origin[1] - bottom * m.resolution) + tuple(m.origin[2:])
    return Grid(data, m.resolution, origin)


def changed_windows(changed: np.ndarray, gap: int) -> List[Tuple[int, int, int, int]]:
    """(r0, r1, c0, c1) windows covering the True cells of `changed`, one per group of cells less
    than `gap` cells apart (their bounding boxes; a window may overlap another)."""
    if not changed.any():
        return []
    near = cv2.dilate(changed.astype(np.uint8), np.ones((gap, gap), np.uint8))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(near, connectivity=8)
    out = []
    for k in range(1, n):
        x, y, w, h = (int(v) for v in stats[k, :4])
        inside = changed[y:y + h, x:x + w] & (labels[y:y + h, x:x + w] == k)
        rows, cols = np.flatnonzero(inside.any(axis=1)), np.flatnonzero(inside.any(axis=0))
        out.append((y + int(rows[0]), y + int(rows[-1]) + 1, x + int(cols[0]), x + int(cols[-1]) + 1))
    return out
