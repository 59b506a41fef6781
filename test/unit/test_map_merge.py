"""Merging robots' maps (maps/merge.py): placement by known initial poses, estimation by matching."""
import math
import os

import numpy as np
import pytest

from mbot_slam_navigation.maps.merge import estimate_pose, merge
from mbot_slam_navigation.nav.frontiers import Grid
from mbot_slam_navigation.sim.ground_truth import rasterize
from mbot_slam_navigation.sim.sdf_world import load_world

HOME = os.path.join(os.path.dirname(__file__), '..', '..', 'worlds', 'mbot_sim_gazebo_navigation.world')


from mbot_slam_navigation.transforms import inverse2d as inverse


@pytest.fixture(scope='module')
def home():
    truth, origin = rasterize(load_world(HOME), 0.05)
    data = np.where(truth > 0, 100, 0).astype(np.int8)
    return Grid(data, 0.05, origin)


def window(g: Grid, x0, x1, y0, y1) -> Grid:
    """The part of g between x0..x1, y0..y1 [m] that a robot has seen; the rest unknown."""
    d = np.full(g.data.shape, -1, np.int8)
    rows, cols = np.indices(g.data.shape)
    x, y = g.centre_of(rows, cols)
    seen = (x >= x0) & (x < x1) & (y >= y0) & (y < y1)
    d[seen] = g.data[seen]
    return Grid(d, g.resolution, g.origin)


def robot_map(world_part: Grid, pose) -> Grid:
    """world_part as a robot whose map frame sits at `pose` in the world would have it."""
    return merge([(world_part, inverse(pose))])


def test_known_poses_put_each_robot_map_where_it_belongs(home):
    a_pose, b_pose = (0.0, 0.0, 0.0), (-3.0, 2.0, math.pi / 2)  # the second robot started facing north
    a = robot_map(window(home, -6, 1, -6, 1), a_pose)
    b = robot_map(window(home, -1, 5, -4, 4), b_pose)
    m = merge([(a, a_pose), (b, b_pose)])
    assert m.resolution == pytest.approx(0.05)
    rows, cols = np.indices(m.data.shape)
    x, y = m.centre_of(rows, cols)
    tr, tc = home.cell_of(x, y)
    inside = home.inside(tr, tc)
    known = (m.data >= 0) & inside
    # everything either robot saw, and it agrees with the world
    assert np.count_nonzero(known) * 0.05 ** 2 > 0.9 * (7 * 7 + 6 * 8 - 2 * 5)
    agree = m.data[known] == home.data[tr[known], tc[known]]
    assert agree.mean() > 0.99
    # a wall one robot sees is never erased by the other's free cells
    walls = known & (home.data[np.clip(tr, 0, home.data.shape[0] - 1), np.clip(tc, 0, home.data.shape[1] - 1)] == 100)
    assert (m.data[walls] == 100).mean() > 0.97
    # outside both windows: unknown
    far = (x > 5.5) & (y < -5.0)
    assert (m.data[far & (m.data >= 0)].size == 0)


def test_matching_estimates_the_second_robot_start_from_the_overlap(home):
    b_pose = (-1.0, 1.5, math.radians(30))
    a = window(home, -6, 2, -6, 1)                             # robot a's map frame is the world
    b = robot_map(window(home, -2, 5, -4, 4), b_pose)
    est, why = estimate_pose(a, b)
    assert est is not None, why
    assert math.hypot(est[0] - b_pose[0], est[1] - b_pose[1]) < 0.1
    assert abs(math.degrees(est[2] - b_pose[2])) < 2.0
    # merged by the estimate, the walls land on the world's walls
    m = merge([(a, (0.0, 0.0, 0.0)), (b, est)])
    rows, cols = np.nonzero(m.data == 100)
    x, y = m.centre_of(rows, cols)
    tr, tc = home.cell_of(x, y)
    near = np.zeros(len(x), bool)
    for dr in (-2, -1, 0, 1, 2):
        for dc in (-2, -1, 0, 1, 2):
            r, c = np.clip(tr + dr, 0, home.data.shape[0] - 1), np.clip(tc + dc, 0, home.data.shape[1] - 1)
            near |= home.data[r, c] == 100
    assert near.mean() > 0.99


def test_matching_refuses_maps_that_do_not_overlap(home):
    a = window(home, -6, -2, -6, -3)
    b = robot_map(window(home, 1.5, 4.5, 1, 3.5), (0.5, 0.5, 1.0))
    est, why = estimate_pose(a, b)
    assert est is None
    assert 'overlap' in why or 'features' in why or 'scales' in why


def test_a_teammate_seen_in_a_doorway_does_not_stay_as_a_wall():
    from mbot_slam_navigation.maps.merge import clear_swept
    d = np.zeros((60, 60), np.int8)
    d[30, :] = 100                                   # a wall along y = 1.5 (cells of 0.05 m)
    d[30, 20:38] = 0                                 # its door, x 1.0 .. 1.9
    rr, cc = np.indices(d.shape)
    ring = np.abs(np.hypot(rr - 30, cc - 29) - 4) < 0.7   # a robot of 0.2 m seen standing in the door
    d[ring] = 100
    d[50:, 50:] = -1
    m = Grid(d, 0.05, (0.0, 0.0))
    trail = [(1.45, 0.5), (1.45, 1.0), (1.48, 1.5), (1.45, 2.5)]   # where that robot drove
    out = clear_swept(m, [trail], 0.25)
    assert not (out.data[ring] == 100).any()         # the ghost is gone
    assert (out.data[30, :19] == 100).all() and (out.data[30, 40:] == 100).all()  # the wall stays
    assert (out.data[50:, 50:] == -1).all()          # unknown stays unknown
    assert clear_swept(m, [trail], 0.0) is m


def test_the_nearest_robot_places_a_wall_both_saw():
    # robot a drove along y = 0.5 and sees the wall at y = 1.5; robot b, 5 m away, sees it 0.1 m off
    # (cells of 0.05 m from y = -4: row 110 is y = 1.5)
    a = np.zeros((160, 80), np.int8)
    a[110, :] = 100
    b = np.zeros((160, 80), np.int8)
    b[112, :] = 100
    ga, gb = Grid(a, 0.05, (0.0, -4.0)), Grid(b, 0.05, (0.0, -4.0))
    at = (0.0, 0.0, 0.0)
    thick = merge([(ga, at), (gb, at)])
    assert (thick.data[110, :] == 100).all() and (thick.data[112, :] == 100).all()   # occupied wins: doubled
    trail_a = [(0.2, 0.5), (3.8, 0.5)]
    trail_b = [(0.2, -3.5), (3.8, -3.5)]
    m = merge([(ga, at), (gb, at)], trails=[trail_a, trail_b])
    assert (m.data[110, :] == 100).all()            # robot a's wall, where a saw it from nearby
    assert (m.data[112, :] == 0).all()              # b's copy, 0.1 m off, is not kept
    # a cell only b knows keeps b's value, however far b was
    a2 = a.copy()
    a2[:, 60:] = -1
    m2 = merge([(Grid(a2, 0.05, (0.0, -4.0)), at), (gb, at)], trails=[trail_a, trail_b])
    assert (m2.data[112, 60:] == 100).all() and (m2.data[110, :60] == 100).all()


def test_a_map_padded_to_blocks_keeps_its_cells_in_place_and_grows_by_blocks():
    from mbot_slam_navigation.maps.merge import padded_to_blocks
    data = np.arange(7 * 9, dtype=np.int8).reshape(7, 9)
    m = Grid(data, 0.05, (-0.35, 0.15))  # not on a block's edge
    p = padded_to_blocks(m, 0.2)  # blocks of 4 cells
    assert p.data.shape[0] % 4 == 0 and p.data.shape[1] % 4 == 0
    r, c = p.cell_of(m.centre_of(3, 5)[0], m.centre_of(3, 5)[1])
    assert p.data[r, c] == data[3, 5]
    assert (p.data == -1).sum() == p.data.size - data.size
    # a map grown by one cell inside the same block keeps the padded size and origin
    m2 = Grid(np.zeros((7, 10), np.int8), 0.05, (-0.35, 0.15))
    p2 = padded_to_blocks(m2, 0.2)
    assert p2.data.shape == p.data.shape and p2.origin == pytest.approx(p.origin)
    assert p.origin == pytest.approx((-0.4, 0.0))  # block edges: multiples of 0.2 m
    # an edge that went out across a block's edge and back: covering what was sent, the size stays
    wide = padded_to_blocks(Grid(np.zeros((7, 10), np.int8), 0.05, (-0.45, 0.15)), 0.2)
    assert wide.data.shape[1] > p.data.shape[1]
    kept = padded_to_blocks(m, 0.2, cover=wide)
    assert kept.data.shape == wide.data.shape and kept.origin == pytest.approx(wide.origin)
    r, c = kept.cell_of(m.centre_of(3, 5)[0], m.centre_of(3, 5)[1])
    assert kept.data[r, c] == data[3, 5]


def test_changes_far_apart_go_in_windows_of_their_own():
    from mbot_slam_navigation.maps.merge import changed_windows
    changed = np.zeros((100, 200), bool)
    changed[10:12, 5:9] = True
    changed[13, 15] = True        # near the first: the same window
    changed[80:90, 150:160] = True
    assert sorted(changed_windows(changed, 20)) == [(10, 14, 5, 16), (80, 90, 150, 160)]
    assert changed_windows(np.zeros((5, 5), bool), 20) == []
