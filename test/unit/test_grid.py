"""The Python wrapper over the core grid: same geometry and errors as the C++ side."""
import math

import numpy as np
import pytest

from mbot_slam_navigation.grid import LogOddsModel, OccupancyGrid, bresenham_line, make_room


def test_world_cell_round_trip_and_bounds():
    grid = OccupancyGrid(100, 50, 0.1, origin=(-5.0, -2.5))
    rng = np.random.default_rng(7)
    for x, y in rng.uniform((-5.0, -2.5), (5.0, 2.5), size=(200, 2)):
        cell = grid.world_to_cell(x, y)
        assert grid.contains(cell)
        cx, cy = grid.cell_center(cell)
        assert abs(cx - x) <= 0.05 + 1e-9 and abs(cy - y) <= 0.05 + 1e-9
    assert not grid.contains(grid.world_to_cell(5.01, 0.0))
    with pytest.raises(IndexError, match='outside'):
        grid.probability((100, 0))


def test_bad_arguments_raise_value_errors():
    with pytest.raises(ValueError, match='resolution'):
        OccupancyGrid(10, 10, 0.0)
    with pytest.raises(ValueError, match='p_hit'):
        LogOddsModel(p_hit=0.3)


def test_bresenham_from_python():
    assert bresenham_line((0, 0), (3, 1)) == [(0, 0), (1, 0), (2, 1), (3, 1)]


def test_scan_into_grid_and_ros_data_layout():
    grid = OccupancyGrid(60, 60, 0.05, origin=(-1.5, -1.5))
    used = grid.integrate_scan((0.0, 0.0, math.pi / 2), 0.0, 0.1, 0.05, 4.0, [1.0], usable_range=3.0)
    assert used == 1
    data = grid.ros_data()
    assert data.shape == (60, 60) and data.dtype == np.int8
    # The pose faces north, so the hit lands 1 m north of the sensor: row index is y.
    hx, hy = grid.world_to_cell(0.0, 1.01)
    assert data[hy, hx] == 70
    assert data[0, 0] == -1


def test_room_raycast_sees_every_wall():
    room = make_room(4.0, 3.0, 0.05)
    angles = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2])
    ranges = room.cast_rays(1.0, 1.0, angles, 10.0)
    np.testing.assert_allclose(ranges, [3.0, 2.0, 1.0, 1.0], atol=1e-6)
    assert math.isinf(room.cast_rays(1.0, 1.0, [0.0], 2.0)[0])
