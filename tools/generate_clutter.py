#!/usr/bin/env python3
"""Generates clutter worlds for navigation without a map (Gazebo SDF), from a level and a seed.

    tools/generate_clutter.py LEVEL [--seed N] [--out DIR]      LEVEL: wide, medium, narrow, all

A walled strip 13 m x 5 m; the robot starts at (0, 0) facing +x and its goal is (10, 0). Between
x = 1.5 and 8.5 m, random cylinders (radius 0.08-0.25 m) and boxes (0.15-0.6 m a side) are added
one by one, each kept only if a robot can still get through: the free space that keeps at least
half the level's narrowest gap from every obstacle must still join start and goal. Obstacles are
added until the clutter covers the level's share of the strip or no more fit. The levels, for the
mbot (0.4 m wide): wide 0.60 m (1.5x its width), 25% covered; medium 0.52 m (1.3x), 30%; narrow
0.46 m (1.15x), 35%. Obstacles may touch the side walls, so the way along them is cluttered too.

Beside DIR/clutter_<level>_<seed>.world, DIR/clutter_<level>_<seed>.yaml holds the start, the goal,
the narrowest gap on the widest way through [m] and the shortest path length for a robot of radius
0.2 m [m] (the ideal time is that over the robot's max_vel_x). The same level and seed give the
same world.
"""
import argparse
import math
import os
import random
import sys
from typing import Tuple

import cv2
import numpy as np
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from generate_world import Plan, rectangle  # noqa: E402  (the same SDF writer as every world)

HERE = os.path.dirname(os.path.abspath(__file__))
LEVELS = {'wide': (0.60, 0.25), 'medium': (0.52, 0.30), 'narrow': (0.46, 0.35)}  # gap [m], share covered
START, GOAL = (0.0, 0.0), (10.0, 0.0)
X0, X1, Y0, Y1 = -1.5, 11.5, -2.5, 2.5        # [m] the strip's walls (centre lines)
CLUTTER_X = (1.5, 8.5)                        # [m] where obstacles go
RES = 0.02                                    # [m] of the grid the checks run on
ROBOT_RADIUS = 0.2                            # [m] the mbot's


class Raster:
    """The strip's obstacles on a grid: 255 where an obstacle is."""

    def __init__(self):
        self.w, self.h = int(round((X1 - X0) / RES)) + 1, int(round((Y1 - Y0) / RES)) + 1
        self.img = np.zeros((self.h, self.w), np.uint8)
        t = max(1, int(round(0.1 / RES)))  # walls 0.1 m thick
        cv2.rectangle(self.img, (0, 0), (self.w - 1, self.h - 1), 255, t)

    def cell(self, x: float, y: float) -> Tuple[int, int]:
        return int(round((x - X0) / RES)), int(round((y - Y0) / RES))

    def add(self, img, shape) -> None:
        kind, x, y, a, b = shape
        if kind == 'cylinder':
            cv2.circle(img, self.cell(x, y), int(math.ceil(a / RES)), 255, -1)
        else:
            p0, p1 = self.cell(x - a / 2, y - b / 2), self.cell(x + a / 2, y + b / 2)
            cv2.rectangle(img, p0, p1, 255, -1)

    def covered(self, xs) -> float:
        """The share of the strip between x = xs[0] and xs[1] that obstacles cover (walls aside)."""
        (c0, _), (c1, _) = self.cell(xs[0], 0.0), self.cell(xs[1], 0.0)
        t = max(1, int(round(0.1 / RES)))
        return float(np.count_nonzero(self.img[t:-t, c0:c1])) / self.img[t:-t, c0:c1].size

    def clearance(self, img) -> np.ndarray:
        """[m] from each free cell to the nearest obstacle cell."""
        return cv2.distanceTransform((img == 0).astype(np.uint8), cv2.DIST_L2, 5) * RES

    def joined(self, ok: np.ndarray) -> bool:
        """Whether start and goal lie in one 8-connected region of `ok`."""
        (sx, sy), (gx, gy) = self.cell(*START), self.cell(*GOAL)
        if not ok[sy, sx] or not ok[gy, gx]:
            return False
        _, labels = cv2.connectedComponents(ok.astype(np.uint8), connectivity=8)
        return labels[sy, sx] == labels[gy, gx]


def bottleneck(r: Raster) -> float:
    """[m] the narrowest gap on the widest way from start to goal (twice the clearance it keeps)."""
    c = r.clearance(r.img)
    lo, hi = 0.0, 2.5
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if r.joined(c >= mid) else (lo, mid)
    return 2 * lo


def shortest_path(r: Raster, radius: float) -> float:
    """[m] the shortest way from start to goal for a round robot of `radius`, or inf."""
    try:
        from mbot_slam_navigation import _core
    except ImportError:
        return float('nan')  # outside the devel space: not computed
    ok = (r.clearance(r.img) >= radius).astype(np.uint8)
    (sx, sy), (gx, gy) = r.cell(*START), r.cell(*GOAL)
    d = _core._path_lengths(ok, sx, sy)
    return float(d[gy, gx]) * RES if d[gy, gx] >= 0 else math.inf


def clutter(level: str, seed: int) -> Tuple[Plan, dict]:
    gap, share = LEVELS[level]
    rng = random.Random('%s-%d' % (level, seed))
    name = 'clutter_%s_%d' % (level, seed)
    p = Plan(name)
    p.walls += rectangle(X0, Y0, X1, Y1)
    p.spawn = (START[0], START[1], 0.0)
    p.room('strip', X0, X1, Y0, Y1)
    r = Raster()
    area = (CLUTTER_X[1] - CLUTTER_X[0]) * (Y1 - Y0)
    covered, attempts, k = 0.0, 0, 0
    while covered < share * area and attempts < 4000:
        attempts += 1
        x, y = rng.uniform(*CLUTTER_X), rng.uniform(Y0, Y1)
        if rng.random() < 0.6:
            shape = ('cylinder', x, y, rng.uniform(0.08, 0.25), 0.0)
        else:
            shape = ('box', x, y, rng.uniform(0.15, 0.6), rng.uniform(0.15, 0.6))
        trial = r.img.copy()
        r.add(trial, shape)
        if not r.joined(r.clearance(trial) >= gap / 2):
            continue
        r.img = trial
        covered = r.covered(CLUTTER_X) * area
        if shape[0] == 'cylinder':
            p.cylinders.append(('obstacle_%d' % k, round(x, 3), round(y, 3), round(shape[3], 3)))
        else:
            p.boxes.append(('obstacle_%d' % k, round(x, 3), round(y, 3), round(shape[3], 3), round(shape[4], 3)))
        k += 1
    info = {'world': name + '.world', 'level': level, 'seed': seed,
            'start': {'x': START[0], 'y': START[1], 'yaw': 0.0}, 'goal': {'x': GOAL[0], 'y': GOAL[1], 'yaw': 0.0},
            'obstacles': k, 'covered_share': round(covered / area, 3),
            'narrowest_gap_m': round(bottleneck(r), 3),
            'shortest_path_m': round(shortest_path(r, ROBOT_RADIUS), 3)}
    return p, info


def write(level: str, seed: int, out: str) -> dict:
    p, info = clutter(level, seed)
    p.write(out, 'tools/generate_clutter.py %s, seed %d' % (level, seed))
    tmp = os.path.join(out, '.%s.yaml.tmp' % p.name)
    with open(tmp, 'w') as f:
        f.write('# Generated by tools/generate_clutter.py %s --seed %d.\n' % (level, seed))
        yaml.safe_dump(info, f, sort_keys=False)
    os.replace(tmp, os.path.join(out, p.name + '.yaml'))
    return info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('level', choices=sorted(LEVELS) + ['all'])
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--out', default=os.path.join(HERE, '..', 'worlds'))
    a = ap.parse_args(argv)
    for level in (sorted(LEVELS) if a.level == 'all' else [a.level]):
        info = write(level, a.seed, a.out)
        print('%s: %d obstacles, %.0f%% covered, narrowest gap %.2f m, shortest path %.2f m'
              % (info['world'], info['obstacles'], 100 * info['covered_share'], info['narrowest_gap_m'],
                 info['shortest_path_m']))


if __name__ == '__main__':
    main()
