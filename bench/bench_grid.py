#!/usr/bin/env python3
"""Occupancy grid hot loops through the Python binding: ray casting and scan integration.

Prints rays per second of grid ray casting (360-beam scans in a 4 m x 3 m room at 0.05 m) and scans
per second of log-odds scan integration, each the median of 5 runs on one core.
"""
import json
import math
import statistics
import time

import numpy as np

from mbot_slam_navigation.grid import OccupancyGrid, make_room


def median_rate(fn, count, runs=5):
    rates = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        rates.append(count / (time.perf_counter() - t0))
    return statistics.median(rates)


def main():
    rng = np.random.default_rng(1)
    room = make_room(4.0, 3.0, 0.05)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    poses = rng.uniform((0.3, 0.3, -math.pi), (3.7, 2.7, math.pi), size=(200, 3))
    scans = [room.cast_rays(x, y, angles + yaw, 6.0) for x, y, yaw in poses]

    def cast():
        for x, y, yaw in poses:
            room.cast_rays(x, y, angles + yaw, 6.0)

    def integrate():
        grid = OccupancyGrid(120, 100, 0.05, origin=(-0.5, -0.5))
        for (x, y, yaw), ranges in zip(poses, scans):
            grid.integrate_scan((x, y, yaw), -math.pi, 2 * math.pi / 360, 0.05, 6.0, ranges, 6.0)

    rays = median_rate(cast, len(poses) * len(angles))
    scans_per_s = median_rate(integrate, len(poses))
    print(json.dumps(dict(benchmark='grid', metric='grid ray casting', value=rays, unit='rays/s',
                          note='median of 5, 360 beams, 4x3 m room')))
    print(json.dumps(dict(benchmark='grid', metric='scan integration', value=scans_per_s, unit='scans/s',
                          note='median of 5, 360 beams, 6 m range')))


if __name__ == '__main__':
    main()
