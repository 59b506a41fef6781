"""The explorer's way out for a stuck robot (nav/escape.py) and its watches (nav/explore_state.py)."""
import math

import numpy as np
import pytest

from mbot_slam_navigation.nav.escape import backtrack_target, escape_command
from mbot_slam_navigation.nav.explore_state import MotionWatch, Plateau


def test_backtrack_target_walks_back_along_the_driven_path():
    # drove east 2 m, then north 1 m into a doorway
    path = [(x * 0.1, 0.0) for x in range(21)] + [(2.0, y * 0.1) for y in range(1, 11)]
    assert backtrack_target(path, (2.0, 1.0), 0.6) == pytest.approx((2.0, 0.4))
    # far enough straight-line, not along the path: around the corner
    assert math.hypot(*np.subtract(backtrack_target(path, (2.0, 1.0), 1.2), (2.0, 1.0))) >= 1.2
    assert backtrack_target(path[:3], (0.2, 0.0), 0.6) is None      # never got that far
    assert backtrack_target([], (0.0, 0.0), 0.6) is None


def test_escape_drives_backwards_to_a_point_behind_and_forwards_to_one_ahead():
    cmd, why = escape_command((0.0, 0.0, 0.0), (-0.6, 0.0), np.zeros((0, 2)), 0.2, 0.1)
    assert why == '' and cmd[0] < 0 and abs(cmd[1]) < 1e-9
    cmd, _ = escape_command((0.0, 0.0, 0.0), (0.6, 0.1), np.zeros((0, 2)), 0.2, 0.1)
    assert cmd[0] > 0 and cmd[1] > 0                                  # ahead and to the left
    cmd, _ = escape_command((0.0, 0.0, 0.0), (-0.6, 0.1), np.zeros((0, 2)), 0.2, 0.1)
    assert cmd[0] < 0 and cmd[1] < 0                                  # backing towards the left turns right
    cmd, _ = escape_command((0.0, 0.0, 0.0), (0.0, 0.6), np.zeros((0, 2)), 0.2, 0.1)
    assert cmd == (0.0, 0.5)                                          # abeam: a disc turns in place first
    assert escape_command((1.0, 1.0, 2.0), (1.05, 1.0), np.zeros((0, 2)), 0.2, 0.1) == (None, 'arrived')


def test_escape_stops_for_what_the_laser_sees_on_the_side_it_moves_to():
    wall_behind = np.array([[-0.25, y] for y in np.linspace(-0.3, 0.3, 13)])
    cmd, why = escape_command((0.0, 0.0, 0.0), (-0.6, 0.0), wall_behind, 0.2, 0.1)
    assert cmd is None and 'behind' in why
    # a wall close in front does not stop it backing away, nor door posts beside it
    posts = np.array([[0.22, 0.0], [0.0, 0.23], [0.0, -0.23]])
    cmd, why = escape_command((0.0, 0.0, 0.0), (-0.6, 0.0), posts, 0.2, 0.1)
    assert cmd is not None and cmd[0] < 0
    # wedged against a table behind-right (0.05 m from the robot's edge): it may drive away from it
    # forwards, though the table lies within the clearance of where it stands
    table = np.array([[-0.1 + 0.02 * i, -0.25] for i in range(-5, 6)])
    cmd, why = escape_command((0.0, 0.0, 0.0), (0.6, 0.0), table, 0.2, 0.1)
    assert cmd is not None and cmd[0] > 0, why


def test_escape_does_not_turn_on_the_spot_beside_a_wall_corner():
    # the kitchen door's jamb corner 0.205 m from the centre, behind-right: the wheels (0.211 m out)
    # would sweep it; a target abeam needs a turn, so the escape says why instead of touching
    corner = np.array([[-0.13, -0.158]])
    cmd, why = escape_command((0.0, 0.0, 0.0), (0.0, 0.6), corner, 0.2, 0.1)
    assert cmd is None and 'turning' in why
    # 0.3 m off, it turns
    cmd, why = escape_command((0.0, 0.0, 0.0), (0.0, 0.6), corner * 1.5, 0.2, 0.1)
    assert cmd == (0.0, 0.5), why


def test_motion_watch_counts_standing_still():
    w = MotionWatch(distance=0.2)
    w.update(0.0, (0.0, 0.0))
    w.update(10.0, (0.1, 0.0))
    assert w.still_for(40.0) == 40.0
    w.update(41.0, (0.25, 0.0))
    assert w.still_for(50.0) == pytest.approx(9.0)


def test_plateau_is_the_longest_stretch_without_growth_while_frontiers_remain():
    p = Plateau(growth=0.5)
    for t, area, left in [(0, 10, True), (10, 12, True), (20, 12.2, True), (50, 12.3, True), (60, 15, True),
                          (70, 15, False), (200, 15, False), (210, 15, True), (220, 15.1, True)]:
        p.update(float(t), float(area), left)
    assert p.longest == pytest.approx(40.0) and p.longest_at == pytest.approx(10.0)
