#!/usr/bin/env python3
"""Costmap benchmark: inflation of a full 4000 x 4000 costmap at 0.05 m (an office-like maze of
rooms and corridors), the tutorial's inflation (inflation_radius 0.6 m, cost_scaling_factor 10,
inscribed radius 0.2 m). Median of 5 runs, one core, through the binding (which copies the 16 MB
grid in and out: included). Target: under 100 ms.
"""
import json
import statistics
import time

import numpy as np

from mbot_slam_navigation import _core


def office_maze(n=4000, room=100, door=20, seed=0):
    """Walls every `room` cells with a door of `door` cells at a random place in each wall."""
    rng = np.random.default_rng(seed)
    g = np.zeros((n, n), np.uint8)
    for k in range(0, n, room):
        g[k, :] = 254
        g[:, k] = 254
        for j in range(0, n, room):
            a = j + rng.integers(5, room - door - 5)
            g[k, a:a + door] = 0
            b = j + rng.integers(5, room - door - 5)
            g[b:b + door, k] = 0
    return g


def main():
    maze = office_maze()
    times = []
    for _ in range(5):
        g = maze.copy()
        t0 = time.perf_counter()
        _core._inflate(g, 0.05, 0.2, 0.6, 10.0)
        times.append(time.perf_counter() - t0)
    print(json.dumps(dict(benchmark='costmap', metric='inflation 4000x4000 at 0.05 m', value=1000 * statistics.median(times),
                          unit='ms', target='< 100', note='median of 5, office maze, radius 0.6 m')))


if __name__ == '__main__':
    main()
