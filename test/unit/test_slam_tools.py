"""CARMEN reading and the relations metric on tiny fixtures."""
import math
import os

import numpy as np
import pytest

from mbot_slam_navigation.slam.carmen import CarmenError, read_log
from mbot_slam_navigation.slam.relations import evaluate, pose_at
from mbot_slam_navigation.transforms import compose2d, relative2d

DATA = os.path.join(os.path.dirname(__file__), '..', 'data')


def test_carmen_lines():
    scans = read_log(os.path.join(DATA, 'tiny.clf'))
    assert len(scans) == 3
    a, b, c = scans
    # 4 beams (even): 180 degrees from -90 in 45-degree steps; 81.91 kept ("no measurement", skipped by maxRange)
    assert a.angle_min == pytest.approx(-math.pi / 2) and a.angle_increment == pytest.approx(math.pi / 4)
    assert a.ranges[2] == pytest.approx(81.91) and a.laser_pose == pytest.approx((0.1, 0.0, 0.0))
    # 5 beams (odd): -90 to +90 inclusive; the laser pose is relative to the robot's odometry
    assert b.angle_increment == pytest.approx(math.pi / 4)
    assert b.odom == pytest.approx((1.0, 0.0, math.pi / 2)) and b.laser_pose == pytest.approx((0.0, -0.1, 0.0), abs=1e-6)
    assert c.time == pytest.approx(10.45) and len(c.ranges) == 5 and c.odom == pytest.approx((2.0, 0.5, 0.0))


def test_carmen_errors_name_the_line():
    with pytest.raises(CarmenError, match=r'short_flaser.clf:1: cannot read FLASER'):
        read_log(os.path.join(DATA, 'short_flaser.clf'))


def test_relations_metric():
    rng = np.random.default_rng(4)
    times = np.arange(0.0, 50.0, 0.5)
    poses = np.cumsum(rng.normal(0, 0.2, size=(len(times), 3)), axis=0)
    rel = []
    for k in range(0, len(times) - 3, 3):
        x, y, yaw = relative2d(poses[k], poses[k + 3])
        rel.append((times[k], times[k + 3], x, y, yaw))
    rel = np.array(rel)
    exact = evaluate(times, poses, rel)
    assert exact.trans_mean == pytest.approx(0.0, abs=1e-9) and exact.rot_mean == pytest.approx(0.0, abs=1e-9)
    # A constant offset of the whole trajectory changes no relative motion...
    moved = np.array([compose2d((5.0, -2.0, 0.7), p) for p in poses])
    assert evaluate(times, moved, rel).trans_mean == pytest.approx(0.0, abs=1e-9)
    # ...while 0.1 m forward added to every estimated step shows as 0.1 m of error.
    stretched = [poses[0]]
    for k in range(1, len(poses)):
        step = relative2d(poses[k - 1], poses[k])
        stretched.append(compose2d(stretched[-1], (step[0] + 0.1 / 3, step[1], step[2])))
    e = evaluate(times, np.array(stretched), rel)
    assert e.trans_mean == pytest.approx(0.1, abs=0.01) and e.count == len(rel)
    assert pose_at(times, poses, 100.0) is None  # no estimate near that time
