"""How alike two maps are: B is aligned onto A (a rigid 2D motion found by a rotation search with
phase correlation for the translation, scored by chamfer distance), then their occupied and free
cells are compared in A's frame, as the exploration tutorial compares myMapFile.pgm with
myHomeMapFile.pgm by eye.

Cells are classified as map_saver does: occupied >= 65, free 0..25, anything else unknown.
"""
import math
from dataclasses import dataclass, asdict
from typing import Tuple

import cv2
import numpy as np

from mbot_slam_navigation.maps.map_io import SAVER_FREE, SAVER_OCCUPIED, LoadedMap


@dataclass
class MapComparison:
    alignment: Tuple[float, float, float]  # B -> A: dx [m], dy [m], dyaw [rad], about A's origin
    occupied_precision: float   # share of B's occupied cells within `tolerance` of A's
    occupied_recall: float      # share of A's occupied cells within `tolerance` of B's
    occupied_f1: float
    free_iou: float             # free in both / free in either, after alignment
    known_area_a: float         # [m^2]
    known_area_b: float         # [m^2]
    tolerance: float            # [m]

    @property
    def similarity(self) -> float:
        """One figure in [0, 1]: the mean of occupied_f1 and free_iou."""
        return 0.5 * (self.occupied_f1 + self.free_iou)

    def as_dict(self) -> dict:
        d = asdict(self)
        d['similarity'] = self.similarity
        return d


def _cell_to_world(m: LoadedMap) -> np.ndarray:
    """3x3 homogeneous transform from (col, row) cell-centre coordinates to world [m]."""
    c, s = math.cos(m.origin[2]), math.sin(m.origin[2])
    r = m.resolution
    return np.array([[c * r, -s * r, m.origin[0] + (c - s) * r / 2],
                     [s * r, c * r, m.origin[1] + (s + c) * r / 2],
                     [0, 0, 1]])


def _rigid(dx: float, dy: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, dx], [s, c, dy], [0, 0, 1]])


class _Canvas:
    """A world-aligned raster covering both maps (with room for B to move) at the finer resolution."""

    def __init__(self, a: LoadedMap, b: LoadedMap, max_cells: int = 1200):
        corners = []
        for m in (a, b):
            h, w = m.data.shape
            t = _cell_to_world(m)
            for col, row in ((-0.5, -0.5), (w - 0.5, -0.5), (-0.5, h - 0.5), (w - 0.5, h - 0.5)):
                corners.append((t @ [col, row, 1])[:2])
        corners = np.array(corners)
        span_b = max(b.data.shape) * b.resolution
        lo, hi = corners.min(0) - span_b / 2, corners.max(0) + span_b / 2
        self.resolution = max(min(a.resolution, b.resolution), float((hi - lo).max()) / max_cells)
        self.origin = lo
        self.size = (int(math.ceil((hi - lo)[0] / self.resolution)), int(math.ceil((hi - lo)[1] / self.resolution)))

    def pixel_to_world(self) -> np.ndarray:
        r = self.resolution
        return np.array([[r, 0, self.origin[0] + r / 2], [0, r, self.origin[1] + r / 2], [0, 0, 1]])

    def render(self, m: LoadedMap, mask: np.ndarray, world_motion: np.ndarray = np.eye(3)) -> np.ndarray:
        """`mask` (a boolean image of m's cells) drawn in the canvas after moving m by world_motion."""
        # canvas pixel -> world -> (undo motion) -> m's cell
        src_from_dst = np.linalg.inv(_cell_to_world(m)) @ np.linalg.inv(world_motion) @ self.pixel_to_world()
        return cv2.warpAffine(mask.astype(np.uint8), src_from_dst[:2], self.size,
                              flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP, borderValue=0) > 0


def _classes(m: LoadedMap):
    d = m.data.astype(np.int16)
    return d >= SAVER_OCCUPIED, (d >= 0) & (d <= SAVER_FREE)


def compare_maps(a: LoadedMap, b: LoadedMap, tolerance: float = 0.1, max_rotation_deg: float = 180.0,
                 align: bool = True) -> Tuple[MapComparison, np.ndarray]:
    """Compares B with A; returns the figures and an overlay image (BGR, top row = highest y):
    A's walls red, B's black-blue, both dark, free space in either light grey."""
    occ_a, free_a = _classes(a)
    occ_b, free_b = _classes(b)
    if not occ_a.any() or not occ_b.any():
        raise ValueError('a map without occupied cells cannot be aligned or compared')
    canvas = _Canvas(a, b)
    ca = canvas.render(a, occ_a)
    dist_a = cv2.distanceTransform((~ca).astype(np.uint8), cv2.DIST_L2, 5) * canvas.resolution
    blur_a = cv2.GaussianBlur(ca.astype(np.float32), (0, 0), 2.0)
    window = cv2.createHanningWindow(canvas.size, cv2.CV_32F)

    # B's occupied centroid: rotations are tried about it, so the translation left is small.
    rows, cols = np.nonzero(occ_b)
    centre = (_cell_to_world(b) @ np.array([cols.mean(), rows.mean(), 1.0]))[:2]

    def motion(yaw, shift):
        return _rigid(*(centre + shift), 0) @ _rigid(0, 0, yaw) @ _rigid(*(-centre), 0)

    def score(m):
        cb = canvas.render(b, occ_b, m)
        return float(np.mean(np.minimum(dist_a[cb], 1.0))) if cb.any() else math.inf

    def best_shift(yaw):
        cb = canvas.render(b, occ_b, motion(yaw, np.zeros(2)))
        (sx, sy), _ = cv2.phaseCorrelate(cv2.GaussianBlur(cb.astype(np.float32), (0, 0), 2.0), blur_a, window)
        return np.array([sx, sy]) * canvas.resolution

    best = (score(np.eye(3)), 0.0, np.zeros(2))
    if align:
        step = 2.0
        yaws = np.radians(np.arange(-max_rotation_deg, max_rotation_deg + 1e-9, step)) if max_rotation_deg > 0 else [0.0]
        for yaw in yaws:
            shift = best_shift(yaw)
            s = score(motion(yaw, shift))
            if s < best[0]:
                best = (s, float(yaw), shift)
        # Refine: finer rotations, then one-cell translation steps, until nothing improves.
        for yaw in best[1] + np.radians(np.arange(-step, step + 1e-9, 0.25)):
            shift = best_shift(yaw)
            s = score(motion(yaw, shift))
            if s < best[0]:
                best = (s, float(yaw), shift)
        improved = True
        while improved:
            improved = False
            for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                shift = best[2] + np.array(d) * canvas.resolution
                s = score(motion(best[1], shift))
                if s < best[0] - 1e-9:
                    best, improved = (s, best[1], shift), True
    m = motion(best[1], best[2]) if align else np.eye(3)

    cb_occ = canvas.render(b, occ_b, m)
    dist_b = cv2.distanceTransform((~cb_occ).astype(np.uint8), cv2.DIST_L2, 5) * canvas.resolution
    tol = tolerance + canvas.resolution / 2  # a wall cell's centre may sit half a cell from the wall
    precision = float(np.mean(dist_a[cb_occ] <= tol))
    recall = float(np.mean(dist_b[ca] <= tol))
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    fa, fb = canvas.render(a, free_a), canvas.render(b, free_b, m)
    union = np.count_nonzero(fa | fb)
    iou = np.count_nonzero(fa & fb) / union if union else 0.0
    result = MapComparison(
        alignment=(float(m[0, 2]), float(m[1, 2]), math.atan2(m[1, 0], m[0, 0])),
        occupied_precision=precision, occupied_recall=recall, occupied_f1=f1, free_iou=float(iou),
        known_area_a=float(np.count_nonzero(occ_a | free_a)) * a.resolution ** 2,
        known_area_b=float(np.count_nonzero(occ_b | free_b)) * b.resolution ** 2, tolerance=tolerance)

    overlay = np.full(ca.shape + (3,), 205, np.uint8)
    overlay[fa | fb] = (245, 245, 245)
    overlay[ca] = (40, 40, 220)
    overlay[cb_occ] = (200, 90, 0)
    overlay[ca & cb_occ] = (40, 40, 40)
    return result, overlay[::-1]
