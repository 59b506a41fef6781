"""The exploration report's figures and files, ROS-free (mbot_slam_navigation.explore_report)."""
import json
import os

import numpy as np
import pytest

from mbot_slam_navigation.explore_report import known_area, reachable_free_space, write_report
from mbot_slam_navigation.nav.frontiers import Grid
from mbot_slam_navigation.sim.ground_truth import rasterize
from mbot_slam_navigation.sim.sdf_world import load_world

WALL_WORLD = os.path.join(os.path.dirname(__file__), '..', '..', 'worlds', 'wall.world')


@pytest.fixture(scope='module')
def world():
    return load_world(WALL_WORLD)


def perfect_map(world):
    truth, origin = rasterize(world, 0.05)
    return Grid(truth.astype(np.int8), 0.05, origin)


def test_reachable_free_space_of_wall_world(world):
    mask, _ = reachable_free_space(world, (0.0, 0.0), 0.2)
    area = mask.sum() * 0.05 ** 2
    # three rooms inside a 10 m x 10 m square, less the inner walls and the pillar
    assert 90.0 < area < 100.0
    with pytest.raises(ValueError, match='within 0.20 m of a shape'):
        reachable_free_space(world, (3.2, -3.0), 0.2)  # inside the pillar


def test_a_perfect_map_scores_full_and_half_a_map_half(world, tmp_path):
    m = perfect_map(world)
    figures = write_report(str(tmp_path), m, [(0.0, 0.0), (1.0, 0.0)], [(1.0, 0.0, True)], [(0.0, 10.0), (5.0, 50.0)],
                           {'outcome': 'complete'}, world, (0.0, 0.0), 0.2)
    assert figures['coverage_of_reachable_free'] == pytest.approx(1.0)
    assert figures['walls_within_tolerance'] == pytest.approx(1.0)
    assert figures['explored_area_m2'] == pytest.approx(known_area(m))
    for name in ('map.pgm', 'map.yaml', 'map.png', 'area.png', 'report.json'):
        assert (tmp_path / name).is_file(), name
    assert json.loads((tmp_path / 'report.json').read_text())['outcome'] == 'complete'
    half = Grid(m.data.copy(), m.resolution, m.origin)
    half.data[:, :half.data.shape[1] // 2] = -1  # the west half never seen
    g = write_report(str(tmp_path / 'half'), half, [], [], [], {}, world, (0.0, 0.0), 0.2)
    assert 0.4 < g['coverage_of_reachable_free'] < 0.6
    wrong = Grid(m.data.copy(), m.resolution, (m.origin[0] + 0.3, m.origin[1] + 0.3))  # walls 0.3 m off
    assert write_report(str(tmp_path / 'off'), wrong, [], [], [], {}, world)['walls_within_tolerance'] < 0.2


def test_a_map_made_from_a_spawn_away_from_the_origin_is_scored_in_the_world_frame(world, tmp_path):
    """A robot spawned at (1, -2) facing +y: its SLAM map (frame at the spawn pose) is the world turned
    by -90 degrees and moved; with the spawn pose the report scores it as the perfect map it is."""
    import cv2
    from mbot_slam_navigation.explore_report import map_in_world
    truth = perfect_map(world)
    spawn = (1.0, -2.0, np.pi / 2)
    # the same cells seen from the map frame: world (x, y) = spawn + R(90) (u, v), so u = y + 2, v = 1 - x
    turned = cv2.rotate(truth.data.astype(np.int16), cv2.ROTATE_90_COUNTERCLOCKWISE).astype(np.int8)
    h, w = truth.data.shape
    x0, y0 = truth.origin
    seen = Grid(turned, 0.05, (y0 + 2.0, 1.0 - (x0 + w * 0.05)))
    back = map_in_world(seen, spawn)
    assert back.origin == pytest.approx(truth.origin, abs=0.051) and back.data.shape[0] in (h, h + 1)
    start = (0.0, 0.0)  # the spawn, in the map frame
    figures = write_report(str(tmp_path), seen, [start], [], [(0.0, 0.0)], {}, world, start, 0.2,
                           world_from_map=spawn)
    assert figures['walls_within_tolerance'] == 1.0 and figures['coverage_of_reachable_free'] > 0.99
    unmoved = write_report(str(tmp_path), seen, [start], [], [(0.0, 0.0)], {}, world, start, 0.2)
    assert unmoved['walls_within_tolerance'] < 0.5  # scored without the spawn pose: wrong
