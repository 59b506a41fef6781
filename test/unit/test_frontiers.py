"""Frontier search and the explorer's decisions, ROS-free (nav/frontiers.py, nav/tour.py,
nav/explore_state.py, nav/team.py)."""
import math

import cv2
import numpy as np
import pytest

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.explore_state import ExploreState
from mbot_slam_navigation.nav.frontiers import Frontier, GivenUp, Grid, frontier_groups, rank_frontiers
from mbot_slam_navigation.nav.team import Teammate, share_out, yields_goal
from mbot_slam_navigation.nav.tour import tour_order

RES = 0.05


def room(width_m=4.0, height_m=3.0, door=None, unknown_beyond=True):
    """A known room (free inside, walls around) inside an unknown 8 x 6 m grid; `door` = (y0, y1) [m]
    opens its east wall. Origin (0, 0); the room spans (1, 1) .. (1 + width, 1 + height)."""
    g = np.full((int(6 / RES), int(8 / RES)), -1 if unknown_beyond else 0, np.int8)
    r0, c0 = int(1 / RES), int(1 / RES)
    r1, c1 = int((1 + height_m) / RES), int((1 + width_m) / RES)
    g[r0:r1 + 1, c0:c1 + 1] = 100
    g[r0 + 1:r1, c0 + 1:c1] = 0
    if door:
        g[int((1 + door[0]) / RES):int((1 + door[1]) / RES), c1] = 0
    return Grid(g, RES, (0.0, 0.0))


def costmap_of(m: Grid, inscribed=0.2, radius=0.6, scaling=10.0) -> Grid:
    """move_base's global costmap of map m in the OccupancyGrid scale (100 lethal, 99 inscribed)."""
    occupied = (m.data >= 65).astype(np.uint8)
    d = cv2.distanceTransform(1 - occupied, cv2.DIST_L2, 5) * RES
    cost = np.zeros(m.data.shape, np.int8)
    ring = (d > inscribed) & (d <= radius)
    cost[ring] = np.clip(98 * np.exp(-scaling * (d[ring] - inscribed)), 1, 98).astype(np.int8)
    cost[d <= inscribed] = 99
    cost[occupied > 0] = 100
    return Grid(cost, RES, m.origin)


def test_path_lengths_binding():
    d = _core._path_lengths(np.ones((3, 4), np.uint8), 0, 0)
    assert d[0, 3] == pytest.approx(3.0) and d[2, 2] == pytest.approx(2 * math.sqrt(2))
    with pytest.raises(ValueError, match='outside'):
        _core._path_lengths(np.ones((3, 4), np.uint8), 9, 0)


def test_a_closed_room_has_no_frontier_and_an_open_door_has_one():
    assert frontier_groups(room()) == []
    groups = frontier_groups(room(door=(1.0, 2.0)))
    assert len(groups) == 1
    cols = groups[0][:, 1]
    assert np.all(cols == int(5 / RES))  # the door cells in the east wall line
    assert len(groups[0]) == pytest.approx(1.0 / RES, abs=1)


def test_any_value_below_occupied_counts_as_known():
    m = room(door=(1.0, 2.0))
    m.data[m.data == 0] = 20  # a probabilistic map: "probably free" everywhere
    assert len(frontier_groups(m)) == 1
    m.data[m.data == 20] = 50
    assert len(frontier_groups(m)) == 1


def test_goal_is_a_clear_reachable_cell_near_the_frontier_not_its_centroid():
    # An L-shaped opening: the frontier runs round a corner, its centroid lies in the wall corner.
    m = room(width_m=4.0, height_m=4.0)
    r1, c1 = int(5 / RES), int(5 / RES)
    m.data[r1 - 20:r1 + 1, c1] = 0   # east wall open along its top 1 m
    m.data[r1, c1 - 20:c1 + 1] = 0   # north wall open along its east 1 m
    c = costmap_of(m)
    frontiers = rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.5)
    assert len(frontiers) == 1
    f = frontiers[0]
    gr, gc = c.cell_of(*f.goal)
    assert c.data[gr, gc] < 50 and m.data[gr, gc] == 0
    assert np.min(np.hypot(f.cells[:, 0] - f.goal[0], f.cells[:, 1] - f.goal[1])) <= 0.4 + RES  # goal_reach, to the cell
    cx, cy = f.cells.mean(axis=0)
    assert math.hypot(cx - f.goal[0], cy - f.goal[1]) > 0.1
    # the path is at least the straight line, and not absurdly longer
    straight = math.hypot(f.goal[0] - 2.0, f.goal[1] - 2.0)
    assert straight - 0.05 <= f.path_m <= 1.3 * straight + 0.2


def test_a_frontier_behind_a_wall_is_not_reachable():
    m = room(door=(1.0, 2.0))
    m.data[int(1 / RES):int(4 / RES) + 1, int(3 / RES)] = 100  # a wall across the room
    c = costmap_of(m)
    assert rank_frontiers(m, c, (2.0, 2.0)) == []      # west of the new wall
    assert len(rank_frontiers(m, c, (4.0, 2.0))) == 1  # east of it, by the door


def test_nearer_and_larger_frontiers_cost_less():
    m = room(width_m=6.0, door=(0.5, 2.5))
    m.data[int(4 / RES), int(1.5 / RES):int(2.0 / RES)] = 0  # a 0.5 m gap in the north wall, west
    c = costmap_of(m)
    f = rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.3, potential_scale=3.0, gain_scale=1.0)
    assert len(f) == 2
    assert f[0].goal[0] < 3.0  # the near small gap wins at potential_scale 3
    g = rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.3, potential_scale=0.1, gain_scale=1.0)
    assert g[0].goal[0] > 6.0  # the large door wins when distance hardly counts
    assert rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.75)[0].goal[0] > 6.0  # the gap is too small


def test_a_long_frontier_counts_no_more_than_gain_size_max():
    # A corridor 1.9 m wide and 22 m long, seen from its west end: its north side open from x = 8.5
    # on (13.5 m of frontier, the edge of the laser's view), a 1 m gap in its north wall at x 1.5..2.5
    # behind the robot (x 4). Uncapped, the long frontier 4.5 m away outweighs the gap 2 m away (the
    # office's lobby behind the start was left for last that way); counted up to 5 m, the gap goes first.
    g = np.full((int(5 / RES), int(24 / RES)), -1, np.int8)
    r0, r1, c0, c1 = int(1 / RES), int(3 / RES), int(1 / RES), int(23 / RES)
    g[r0:r1 + 1, c0:c1 + 1] = 100
    g[r0 + 1:r1, c0 + 1:c1] = 0
    g[r1, int(1.5 / RES):int(2.5 / RES)] = 0   # the gap
    g[r1, int(8.5 / RES):c1] = 0               # the open side
    m = Grid(g, RES, (0.0, 0.0))
    c = costmap_of(m)
    uncapped = rank_frontiers(m, c, (4.0, 2.0), min_frontier_size=0.5)
    assert len(uncapped) == 2
    assert uncapped[0].size_m > 10.0 and uncapped[0].goal[0] > 8.0
    capped = rank_frontiers(m, c, (4.0, 2.0), min_frontier_size=0.5, gain_size_max=5.0)
    assert capped[0].goal[0] < 3.0 and capped[0].size_m < 1.5
    assert capped[1].size_m == pytest.approx(uncapped[0].size_m)  # the size itself is kept
    assert capped[1].cost == pytest.approx(3.0 * capped[1].path_m - 5.0)


def test_blacklisted_places_are_avoided():
    m = room(door=(1.0, 2.0))
    c = costmap_of(m)
    f = rank_frontiers(m, c, (2.0, 2.0))
    dropped = []
    assert rank_frontiers(m, c, (2.0, 2.0), avoid=[f[0].goal], avoid_radius=1.5, unreachable=dropped) == []
    # not silently: the report says which frontier is left out, and why
    assert len(dropped) == 1 and dropped[0].x == pytest.approx(5.0, abs=0.1) and dropped[0].size_m >= 0.9
    assert 'farther than 1.5 m from places visited or given up' in dropped[0].why


def test_places_reached_are_left_out_while_other_frontiers_remain_but_not_for_good():
    s = ExploreState(blacklist_timeout=60.0, max_tries=2)
    s.choose(0.0, [frontier_at(2.0, 2.0)], (0.0, 0.0))
    s.reached(10.0)                        # its frontier vanished on the way
    s.choose(11.0, [frontier_at(5.0, 5.0)], (2.0, 2.0))
    s.fail(20.0)
    s.choose(90.0, [frontier_at(5.0, 5.0)], (2.0, 2.0))
    s.fail(100.0)                          # failed twice: for good
    assert set(s.avoid(1e6)) == {(2.0, 2.0), (5.0, 5.0)}
    assert set(s.avoid_for_good()) == {(5.0, 5.0)}
    # A room seen from its door (the goal reached there), whose frontier came back when the map was
    # corrected: left out of the ranking while there is anything else, ranked when it is all there is.
    m = room(door=(1.0, 2.0))
    c = costmap_of(m)
    door_goal = rank_frontiers(m, c, (2.0, 2.0))[0].goal
    t = ExploreState()
    t.choose(0.0, [Frontier(np.array([door_goal]), 1.0, door_goal, 1.0, 1.0)], (2.0, 2.0))
    t.reached(10.0)
    assert rank_frontiers(m, c, (2.0, 2.0), avoid=t.avoid(20.0), avoid_radius=1.5) == []
    assert len(rank_frontiers(m, c, (2.0, 2.0), avoid=t.avoid_for_good(), avoid_radius=1.5)) == 1


def frontier_at(x, y, cost=1.0):
    return Frontier(np.array([[x, y]]), 1.0, (x, y), 1.0, cost)


def test_state_keeps_its_goal_unless_clearly_beaten():
    s = ExploreState(hysteresis=1.0)
    a, b = frontier_at(1.0, 1.0, cost=5.0), frontier_at(5.0, 5.0, cost=4.5)
    assert s.choose(0.0, [a], (0.0, 0.0)) is a
    assert s.choose(3.0, [b, a], (0.0, 0.0)) is None           # better by 0.5 only: keep a
    c = frontier_at(5.0, 5.0, cost=3.0)
    assert s.choose(6.0, [c, a], (0.0, 0.0)) is c               # better by 2: switch
    moved = frontier_at(5.5, 5.0, cost=3.0)
    moved.cells = np.array([[5.0, 5.0], [5.5, 5.0]])
    assert s.choose(9.0, [moved], (0.0, 0.0)) is moved          # same frontier, goal moved: follow it
    assert s.choose(12.0, [], (0.0, 0.0)) is None and s.goal is None


def test_a_goal_left_for_a_better_one_does_not_take_the_robot_back_for_a_while():
    # Two frontiers whose costs take turns as the map grows: the robot left A for B and must not
    # turn back to A while B's frontier is still there, only after switch_back_after.
    s = ExploreState(hysteresis=1.0, switch_back_after=60.0)
    a, b = frontier_at(1.0, 1.0, cost=5.0), frontier_at(5.0, 5.0, cost=3.0)
    assert s.choose(0.0, [a], (0.0, 0.0)) is a
    assert s.choose(3.0, [b, a], (0.0, 0.0)) is b and 'cost 3.0 against 5.0' in s.why
    a_cheap, b_dear = frontier_at(1.0, 1.0, cost=1.0), frontier_at(5.0, 5.0, cost=6.0)
    for t in (6.0, 30.0, 62.0):
        assert s.choose(t, [a_cheap, b_dear], (0.0, 0.0)) is None and s.goal.goal == (5.0, 5.0)
    assert s.choose(64.0, [a_cheap, b_dear], (0.0, 0.0)) is a_cheap  # 61 s after it was left
    # a frontier that is gone frees the robot at once, whatever it left before
    s2 = ExploreState(hysteresis=1.0)
    s2.choose(0.0, [a], (0.0, 0.0))
    s2.choose(3.0, [b, a], (0.0, 0.0))
    assert s2.choose(6.0, [a_cheap], (0.0, 0.0)) is a_cheap and 'is gone' in s2.why


def test_another_frontier_with_the_goal_being_driven_to_is_not_a_new_goal():
    s = ExploreState(hysteresis=1.0, max_goals_per_place=2)
    a = frontier_at(2.0, 1.0, cost=6.0)
    assert s.choose(0.0, [a], (0.0, 0.0)) is a
    for k in range(1, 5):
        # the frontier split: a second group of cells far from the goal, served by the same goal cell
        other = Frontier(np.array([[2.0, 2.5 + 0.01 * k]]), 3.0, (2.02, 1.0), 1.5, 1.5)
        assert s.choose(3.0 * k, [other, a], (0.0, 0.0)) is None
    assert s.goals_chosen == 1
    assert s.screen(15.0, [a])[0] == [a]  # not given up as "sent again and again"


def test_failures_blacklist_expire_and_then_stick():
    s = ExploreState(blacklist_timeout=60.0, max_tries=2, progress_timeout=30.0)
    a = frontier_at(1.0, 1.0)
    s.choose(0.0, [a], (0.0, 0.0))
    s.fail(10.0)
    assert s.avoid(20.0) == [(1.0, 1.0)] and s.screen(20.0, [a]) == ([], 1, [])
    assert s.avoid(71.0) == [] and s.screen(71.0, [a]) == ([a], 0, [])  # expired: may be tried again
    s.choose(71.0, [a], (0.0, 0.0))
    s.fail(72.0)
    assert set(s.avoid(1000.0)) == {(1.0, 1.0)}                     # failed twice: for good
    eligible, waiting, given_up = s.screen(1000.0, [a])
    assert eligible == [] and waiting == 0 and '2 goals failed' in given_up[0].why


def test_no_progress_gives_the_goal_up_and_reached_goals_are_not_sent_again():
    s = ExploreState(progress_timeout=30.0, progress_distance=0.2)
    s.choose(0.0, [frontier_at(3.0, 0.0)], (0.0, 0.0))
    assert not s.stuck(20.0, (0.1, 0.0))
    assert not s.stuck(25.0, (0.3, 0.0))   # moved 0.3 m: the clock restarts
    assert not s.stuck(50.0, (0.35, 0.0))
    assert s.stuck(56.0, (0.35, 0.0)) and s.goal is None and s.avoid(57.0) == [(3.0, 0.0)]
    t = ExploreState()
    t.choose(0.0, [frontier_at(2.0, 2.0)], (0.0, 0.0))
    t.reached(10.0)
    assert t.avoid(1e6) == [(2.0, 2.0)]


def test_unknown_space_inside_furniture_makes_no_frontier_when_asked():
    m = room(width_m=5.0, height_m=4.0, door=(1.0, 2.0))
    r, c = int(2.5 / RES), int(2.5 / RES)
    m.data[r:r + 12, c:c + 20] = 100     # a 1.0 m x 0.6 m table seen from two sides...
    m.data[r + 1:r + 11, c + 1:c + 19] = -1  # ...whose inside nobody sees
    m.data[r + 1:r + 11, c + 19] = 0      # and whose east face is not mapped yet
    assert len(frontier_groups(m)) == 2
    groups = frontier_groups(m, min_unknown_area=3.0)
    assert len(groups) == 1 and np.all(groups[0][:, 1] == int(6 / RES))  # the door only


def test_floor_in_a_shadow_makes_a_frontier_though_small_and_enclosed():
    # A room's corner beside its door, not seen from the doorway: 1.0 m x 1.2 m of unknown floor
    # bounded by the walls on two sides and by seen floor on the other two. Furniture is bounded
    # by what the laser saw of it (the test above); this by free space, so it is explored.
    m = room(width_m=4.0, height_m=3.0)
    m.data[int(1.05 / RES):int(2.25 / RES), int(1.05 / RES):int(2.05 / RES)] = -1
    groups = frontier_groups(m, min_unknown_area=3.0)
    assert len(groups) == 1 and len(groups[0]) * RES > 2.0
    # a speck of unknown in the open (0.15 m square: a cell the laser skipped) is no frontier
    s = room(width_m=4.0, height_m=3.0)
    s.data[int(2.0 / RES):int(2.15 / RES), int(3.0 / RES):int(3.15 / RES)] = -1
    assert frontier_groups(s, min_unknown_area=3.0) == []
    # a map known up to its west and south edges but not its north one (the known cells' own
    # bounding box touches the grid's edge: that component is not a shadow to look at)
    k = room(width_m=4.0, height_m=3.0, unknown_beyond=False)
    k.data[-10:, :] = -1
    k.data[int(1.05 / RES):int(2.25 / RES), int(1.05 / RES):int(2.05 / RES)] = -1
    assert len(frontier_groups(k, min_unknown_area=3.0)) == 2  # the shadow, and the unknown band along the edge


def test_a_corner_in_the_shadow_of_a_door_jamb_makes_a_frontier_though_walls_hold_most_of_its_rim():
    # A right triangle of unknown floor in a room's corner, against two walls (legs 1.5 and 1.2 m):
    # under half of its rim is open floor, but that part is one straight edge 1.9 m long (the
    # home's kitchen beside its door). A table seen from one side is bounded by its faces instead.
    m = room(width_m=4.0, height_m=3.0)
    rows, cols = np.indices(m.data.shape)
    x, y = (cols + 0.5) * RES, (rows + 0.5) * RES
    corner = (x > 1.05) & (y > 1.05) & ((x - 1.0) / 1.5 + (y - 1.0) / 1.2 < 1.0)
    m.data[corner] = -1
    groups = frontier_groups(m, min_unknown_area=3.0)
    assert len(groups) == 1 and len(groups[0]) * RES > 1.2  # 28 cells along the diagonal


def test_a_robot_inside_the_inscribed_zone_still_reaches_out_and_reachable_area_is_reported():
    m = room(door=(1.0, 2.0))
    m.data[int(2.0 / RES):int(2.4 / RES), int(2.12 / RES)] = 100  # a post 0.12 m east of the robot
    c = costmap_of(m)
    rr, rc = c.cell_of(2.0, 2.2)
    assert c.data[rr, rc] == 99                                       # the robot stands in the inscribed zone
    stats = {}
    f = rank_frontiers(m, c, (2.0, 2.2), stats=stats)
    assert len(f) == 1 and stats['reachable_m2'] > 5.0
    stats = {}
    assert rank_frontiers(m, c, (2.0, 2.2), escape_radius=0.0, stats=stats) == []  # without the escape: boxed in
    assert stats['reachable_m2'] < 0.01


def test_a_failed_goal_is_not_sent_again_whatever_goal_its_frontier_yields_next():
    # The door's frontier: its goal failed (the robot could not get there). Next time the frontier
    # has grown and yields a goal 0.1 m from the failed one: neither that goal nor the frontier may
    # be sent while blacklisted, and after max_tries the frontier is given up, with the reason.
    m = room(door=(1.0, 2.0))
    c = costmap_of(m)
    s = ExploreState(blacklist_timeout=60.0, max_tries=2)
    f = rank_frontiers(m, c, (2.0, 2.0))
    assert s.choose(0.0, f, (2.0, 2.0)) is f[0]
    s.fail(30.0, 'no progress for 30 s')
    # without avoid, rank_frontiers yields the same goal again; with avoid_goals no goal within
    # blacklist_radius of it
    again = rank_frontiers(m, c, (2.0, 2.0), avoid_goals=s.avoid_goals(31.0), avoid_radius=s.blacklist_radius)
    for g in again:
        assert math.hypot(g.goal[0] - f[0].goal[0], g.goal[1] - f[0].goal[1]) >= s.blacklist_radius - RES
    # the same frontier, grown by 0.5 m to the north and with its goal 0.1 m off: it waits
    grown = Frontier(np.vstack([f[0].cells, f[0].cells[-10:] + [0.0, 0.5]]), f[0].size_m + 0.5,
                     (f[0].goal[0], f[0].goal[1] + 0.1), f[0].path_m, f[0].cost)
    eligible, waiting, given_up = s.screen(31.0, [grown])
    assert (eligible, waiting, given_up) == ([], 1, [])
    # far from it, another frontier is not held back
    other = frontier_at(-5.0, -5.0)
    assert s.screen(31.0, [grown, other])[0] == [other]
    # after blacklist_timeout it may be tried once more; a second failure gives it up for good
    eligible, waiting, _ = s.screen(91.0, [grown])
    assert eligible == [grown] and waiting == 0
    s.choose(91.0, [grown], (2.0, 2.0))
    s.fail(121.0, 'move_base: no valid plan')
    eligible, waiting, given_up = s.screen(1e6, [grown])
    assert eligible == [] and waiting == 0 and len(given_up) == 1
    assert 'move_base: no valid plan' in given_up[0].why and given_up[0].size_m == pytest.approx(grown.size_m)


def test_a_frontier_behind_a_gap_narrower_than_the_robot_is_reported_unreachable():
    m = room(door=(1.0, 1.25))  # a 0.25 m gap; the robot's inscribed radius is 0.2 m
    # what the laser saw through the gap: 1 m of floor beyond it, then unknown
    m.data[int(1.5 / RES):int(2.75 / RES), int(5.0 / RES) + 1:int(6.0 / RES)] = 100
    m.data[int(1.5 / RES) + 1:int(2.75 / RES) - 1, int(5.0 / RES) + 1:int(6.0 / RES)] = 0
    c = costmap_of(m)
    unreachable = []
    assert rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.2, unreachable=unreachable) == []
    assert len(unreachable) == 1 and isinstance(unreachable[0], GivenUp)
    u = unreachable[0].as_dict()
    assert u['x'] == pytest.approx(6.0, abs=0.1) and 'unreachable' in u['why']


def test_a_frontier_still_there_after_its_goal_was_reached_is_given_up_not_chased():
    # unknown space behind a bathtub: the robot stood at the goal, the frontier is still there
    s = ExploreState()
    f = Frontier(np.array([[3.0 + 0.05 * i, 0.5] for i in range(20)]), 1.0, (3.2, 0.1), 5.0, 14.0)
    s.choose(0.0, [f], (0.0, 0.0))
    s.reached(80.0, arrived=True)
    # next cycle: the same cells, a goal 0.7 m further along: reached once, it may be tried once
    # more (at a doorway a step more may show the room)
    again = Frontier(f.cells[2:], 0.9, (3.9, 0.1), 0.7, 1.2)
    assert s.screen(83.0, [again], map_time=82.0)[0] == [again]
    assert s.choose(83.0, [again], (3.2, 0.1)) is again
    s.reached(100.0, arrived=True)
    # reached twice: on a map from before the arrival it waits, on a later one it is given up
    assert s.screen(101.0, [again], map_time=99.0) == ([], 1, [])
    eligible, waiting, given_up = s.screen(103.0, [again], map_time=102.0)
    assert eligible == [] and waiting == 0 and 'reached 2 times' in given_up[0].why
    # no newer map comes (SLAM publishes none while the robot stands still): it waits settle_time,
    # no longer (a home run once waited for ever)
    assert s.screen(105.0, [again], map_time=99.0)[1] == 1
    eligible, waiting, given_up = s.screen(111.0, [again], map_time=99.0)
    assert waiting == 0 and len(given_up) == 1
    # a frontier nearby that is new (a doorway seen from there) is not held back
    door = Frontier(np.array([[3.3, 1.0 + 0.05 * i] for i in range(20)]), 1.0, (3.3, 0.6), 0.5, 0.5)
    assert s.screen(81.0, [door])[0] == [door]
    # a long frontier (a hall beyond laser range) of which the robot reached one end is not given up
    u = ExploreState()
    arc = Frontier(np.array([[0.05 * i, 3.0] for i in range(300)]), 15.0, (0.3, 2.6), 3.0, -6.0)
    u.choose(0.0, [arc], (0.0, 0.0))
    u.reached(40.0, arrived=True)
    rest = Frontier(arc.cells[40:], 13.0, (2.6, 2.6), 2.0, -7.0)
    assert u.screen(41.0, [rest])[0] == [rest]
    # a frontier that vanished on the way gives nothing up
    t = ExploreState()
    t.choose(0.0, [f], (0.0, 0.0))
    far = frontier_at(-5.0, -5.0)
    assert t.choose(10.0, [far], (0.0, 0.0)) is far  # f's frontier is gone: visited, no cells kept
    assert t.screen(11.0, [again])[0] == [again]


def test_a_frontier_still_there_where_the_robot_stood_gets_its_next_goal_elsewhere():
    # A room with its door in the east wall and, beside the door, a corner of floor the robot did
    # not see from the doorway (the home's kitchen). The robot came from the hall east of it.
    m = room(width_m=4.0, height_m=3.0, door=(1.0, 2.0), unknown_beyond=False)
    m.data[int(1.05 / RES):int(1.95 / RES), int(3.5 / RES):int(4.95 / RES)] = -1
    c = costmap_of(m)
    s = ExploreState()
    first = rank_frontiers(m, c, (6.5, 2.5), min_unknown_area=3.0)
    assert len(first) == 1 and s.choose(0.0, first, (6.5, 2.5)) is first[0]
    s.reached(30.0, arrived=True)
    # the map made there still has the corner unknown: the next goal is not where the robot stands
    again = rank_frontiers(m, c, first[0].goal, min_unknown_area=3.0, avoid=s.avoid(33.0),
                           avoid_radius=s.blacklist_radius, avoid_goals=s.avoid_goals(33.0))
    assert len(again) == 1
    assert math.hypot(again[0].goal[0] - first[0].goal[0], again[0].goal[1] - first[0].goal[1]) >= s.blacklist_radius - RES
    assert again[0].goal[0] < 5.0  # in the room: not in the hall across the wall from the corner
    eligible, waiting, given_up = s.screen(33.0, again, map_time=32.0)
    assert eligible == again and given_up == []
    assert s.choose(33.0, eligible, first[0].goal) is again[0]
    # stood at twice and still there: given up, with why
    s.reached(50.0, arrived=True)
    eligible, waiting, given_up = s.screen(53.0, again, map_time=52.0)
    assert eligible == [] and 'reached 2 times' in given_up[0].why


def test_a_sliver_of_unknown_the_laser_grazed_is_not_worth_a_trip_but_the_grids_edge_is():
    m = room(width_m=4.0, height_m=3.0, door=(1.0, 2.0), unknown_beyond=False)
    m.data[int(2.5 / RES), int(2.0 / RES):int(3.2 / RES)] = -1   # one row of cells, 1.2 m: 0.06 m^2
    m.data[int(2.0 / RES):int(3.0 / RES), -1] = -1                  # at the SLAM map's east edge: 0.05 m^2
                                                                    # in the grid, and what lies beyond it
    c = costmap_of(m)
    assert len(rank_frontiers(m, c, (2.0, 2.0))) == 2
    unreachable = []
    f = rank_frontiers(m, c, (2.0, 2.0), min_unknown_beside=0.25, unreachable=unreachable)
    assert len(f) == 1 and np.all(f[0].cells[:, 0] > 7.8)          # the edge
    assert f[0].unknown_m2 > 1.0
    assert len(unreachable) == 1 and 'only 0.06 m^2 unknown' in unreachable[0].why
    assert unreachable[0].as_dict()['y'] == pytest.approx(2.5, abs=0.1)


def test_two_frontiers_pulling_the_robot_to_and_fro_end_after_max_goals_per_place():
    # A is near and cheap but never gets explored (its goal is "reached" each time from afar and
    # its cells move a little); B is far. Greedy choice alone would alternate forever (the office
    # run that timed out after 208 goals).
    s = ExploreState(max_goals_per_place=4, hysteresis=1.0)
    a = lambda k: Frontier(np.array([[21.8 + 0.05 * i, 4.6 + 0.01 * k] for i in range(50)]), 2.5,
                           (21.78, 4.33 + 0.05 * (k % 3)), 2.0, 3.5)
    b = Frontier(np.array([[17.3, 3.7 + 0.05 * i] for i in range(200)]), 10.0, (17.28, 3.68), 12.0, 26.0)
    sent_a = 0
    for k in range(40):
        eligible, _, given_up = s.screen(10.0 * k, [a(k), b])
        g = s.choose(10.0 * k, eligible, (21.0, 4.0))
        if g is not None and g.goal[0] > 20:
            sent_a += 1
            s.reached(10.0 * k + 5)  # its frontier vanished from under the goal and came back
        if given_up:
            break
    assert sent_a == 4 and 'sent 4 times' in given_up[0].why


def _frontier_at(x, y, path_m, size_m=2.0, potential_scale=3.0):
    return Frontier(np.array([[x, y]]), size_m, (x, y), path_m, potential_scale * path_m - size_m)


def test_the_tour_finishes_the_dead_end_side_before_crossing_to_the_other():
    # a corridor 10 m long; the robot at x = 5; a small frontier 1 m west at the dead end, three
    # east: greedy goes east first (0.8 m) and must come all the way back for the west one
    passable = np.zeros((20, 220), np.uint8)
    passable[5:15, 5:215] = 1
    grid = Grid(passable.astype(np.int8), RES, (0.0, 0.0))
    west = _frontier_at(4.0, 0.5, 1.0, size_m=1.0)
    east = [_frontier_at(x, 0.5, x - 5.0, size_m=1.0) for x in (5.8, 7.0, 8.5)]
    greedy = sorted([west] + east, key=lambda f: f.cost)
    assert greedy[0].goal == (5.8, 0.5)
    toured = tour_order([west] + east, passable, grid)
    assert toured[0].goal == (4.0, 0.5)
    # its cost: its own plus the tour on from it (west end to 8.5 m: 4.5 m), potential_scale 3
    assert toured[0].cost == pytest.approx(west.cost + 3.0 * 4.5, abs=0.3)
    # a wall across the corridor at x = 6 with a door at its far end: the tour measures paths, not lines
    walled = passable.copy()
    walled[5:13, 119:121] = 0
    assert tour_order([west] + east, walled, grid)[0].goal == (4.0, 0.5)
    # a goal off the passable grid (found on a costmap larger than this one): ranked, not a crash
    # (the explorer died with an IndexError here on the large floor)
    beyond = _frontier_at(30.0, 0.5, 25.0, size_m=1.0)
    assert [f.goal for f in tour_order([west, beyond] + east, passable, grid)][-1] == (30.0, 0.5)
    # one frontier, or tours switched off: unchanged
    assert tour_order([west], passable, grid) == [west]
    assert tour_order(greedy, passable, grid, size=0) == greedy


def test_the_tour_takes_a_small_frontier_behind_the_robot_before_twelve_larger_ones_ahead():
    # The office's long trips: the tour saw only the 8 best by greedy cost, so a small frontier
    # the robot passed was left for last and the robot came back across the floor for it. Here a
    # 0.8 m frontier 1.5 m behind the robot is the 12th best greedily; twelve 10 m ones lie 2-4.75 m
    # ahead.
    passable = np.zeros((20, 400), np.uint8)
    passable[5:15, 5:395] = 1
    grid = Grid(passable.astype(np.int8), RES, (0.0, 0.0))
    behind = _frontier_at(3.5, 0.5, 1.5, size_m=0.8)
    ahead = [_frontier_at(5.0 + d, 0.5, d, size_m=10.0) for d in np.arange(2.0, 4.76, 0.25)]
    greedy = sorted([behind] + ahead, key=lambda f: f.cost)
    assert [f.goal for f in greedy].index(behind.goal) == 11
    assert tour_order([behind] + ahead, passable, grid)[0].goal == behind.goal
    # the 8 best only: it is left behind
    assert tour_order([behind] + ahead, passable, grid, size=8)[0].goal != behind.goal


def test_the_tour_measures_the_way_round_a_wall_not_the_straight_line():
    # Two goals 1 m apart on either side of a wall that ends 2 m up: the way round is about 4.6 m.
    passable = np.zeros((60, 200), np.uint8)
    passable[5:55, 5:195] = 1
    passable[:45, 98:102] = 0  # the wall, 0.2 m thick, from the floor's edge to y = 2.25 m
    grid = Grid(passable.astype(np.int8), RES, (0.0, 0.0))
    a, b = _frontier_at(4.45, 0.5, 1.0, size_m=1.0), _frontier_at(5.55, 0.5, 6.0, size_m=1.0)
    toured = {f.goal: f.cost for f in tour_order([a, b], passable, grid, potential_scale=1.0)}
    way = toured[a.goal] - a.cost  # the tour from a on: a to b
    assert 4.0 < way < 5.0
    assert toured[b.goal] - b.cost == pytest.approx(way)
    # a goal off the grid (from a costmap of another cycle): no path known; via the robot
    off = _frontier_at(50.0, 0.5, 8.0, size_m=1.0)
    toured = {f.goal: f.cost for f in tour_order([a, off], passable, grid, potential_scale=1.0)}
    assert toured[a.goal] - a.cost == pytest.approx(1.0 + 8.0)


def test_a_team_shares_the_frontiers_out():
    near_mate = _frontier_at(5.0, 0.0, 5.0)        # 5 m away by path; the teammate stands 1 m from it
    mine = _frontier_at(-3.0, 0.0, 3.0)            # 3 m away; the teammate is 9 m from it
    claimed = _frontier_at(0.0, 6.0, 6.0, 10.0)    # the teammate's goal is 0.5 m from it
    mate = Teammate('robot2', (6.0, 0.0), (0.0, 6.5))
    alone, n = share_out([near_mate, claimed, mine], [])
    assert n == 0 and [f.goal for f in alone] == [mine.goal, claimed.goal, near_mate.goal]  # by cost
    ours, n = share_out(sorted([near_mate, claimed, mine], key=lambda f: f.cost), [mate])
    assert n == 1                                   # the claimed one is left to robot2
    assert [f.goal for f in ours] == [mine.goal, near_mate.goal]
    # the frontier nearer to robot2 costs 3 x (5 m - 1 m) more
    assert ours[1].cost == pytest.approx(near_mate.cost + 3.0 * 4.0)
    # two robots heading for one place: the name that sorts first keeps it
    assert yields_goal((0.2, 6.4), 'robot3', [mate])
    assert not yields_goal((0.2, 6.4), 'robot1', [mate])
    assert not yields_goal((3.0, 0.0), 'robot3', [mate])


def test_the_team_report_is_complete_only_when_every_robot_is():
    from mbot_slam_navigation.explore_report import team_figures
    a = {'outcome': 'complete', 'exploration_time_s': 200.0, 'distance_m': 30.0, 'goals_sent': 10, 'collisions': 0}
    b = {'outcome': 'complete', 'exploration_time_s': 240.5, 'distance_m': 25.5, 'goals_sent': 8, 'collisions': 1,
         'given_up': [{'x': 1.0, 'y': 2.0, 'size_m': 0.8, 'why': 'unreachable'}]}
    f = team_figures({'robot1': a, 'robot2': b})
    assert f['outcome'] == 'complete' and f['robots'] == 2
    assert f['exploration_time_s'] == 240.5 and f['distance_m'] == pytest.approx(55.5)
    assert f['goals_sent'] == 18 and f['collisions'] == 1 and len(f['given_up']) == 1
    assert f['per_robot']['robot2']['distance_m'] == 25.5
    assert team_figures({'robot1': a, 'robot2': dict(b, outcome='timeout')})['outcome'] == 'timeout'
    assert team_figures({'robot1': a, 'robot2': {'outcome': 'not_started'}})['outcome'] == 'not_started'
    # a robot the base station lost (its host died): the team finished without it and names it
    lost = team_figures({'robot1': a, 'robot2': {'outcome': 'lost', 'why': 'silent'}})
    assert lost['outcome'] == 'complete' and lost['robots_lost'] == ['robot2']
    assert lost['per_robot']['robot2']['outcome'] == 'lost' and f['robots_lost'] == []
    assert team_figures({'robot1': dict(a, outcome='stuck'), 'robot2': {'outcome': 'lost'}})['outcome'] == 'stuck'


def test_the_goal_being_driven_to_stays_the_frontiers_goal_while_it_is_still_valid():
    # A frontier 2.6 m long (the room's east side open): its goal is the cell nearest the robot by
    # path, which changes end as the robot moves; the goal being driven to is kept while it can be.
    m = room(door=(0.2, 2.8))
    c = costmap_of(m)
    south = rank_frontiers(m, c, (4.2, 1.5))[0].goal
    north = rank_frontiers(m, c, (4.2, 3.5))[0].goal
    assert north[1] - south[1] > 1.0
    kept = rank_frontiers(m, c, (4.2, 3.5), keep_goal=south)[0]
    assert kept.goal == south and kept.path_m > rank_frontiers(m, c, (4.2, 3.5))[0].path_m
    # a goal that is no cell of the frontier any more (inside the room, far from it) is not kept
    assert rank_frontiers(m, c, (4.2, 3.5), keep_goal=(2.0, 2.0))[0].goal == north


def _hall_with_doors(seed=3, doors=12):
    """A known 20 x 12 m hall walled round, inside an unknown 24 x 16 m grid, with `doors` 1 m gaps
    in its walls at seeded places, each a frontier to the unknown beyond."""
    rng = np.random.default_rng(seed)
    g = np.full((int(16 / RES), int(24 / RES)), -1, np.int8)
    r0, c0, r1, c1 = int(2 / RES), int(2 / RES), int(14 / RES), int(22 / RES)
    g[r0:r1 + 1, c0:c1 + 1] = 100
    g[r0 + 1:r1, c0 + 1:c1] = 0
    for k in range(doors):
        n = 20  # cells: 1 m
        if k % 2:  # north or south wall
            c = int(rng.integers(c0 + 1, c1 - n)) // 40 * 40 + c0 + 10
            g[r0 if k % 4 == 1 else r1, c:c + n] = 0
        else:      # west or east wall
            r = int(rng.integers(r0 + 1, r1 - n)) // 40 * 40 + r0 + 10
            g[r:r + n, c0 if k % 4 == 0 else c1] = 0
    return Grid(g, RES, (0.0, 0.0))


def test_ranking_only_the_best_gives_them_as_ranking_all_does():
    m = _hall_with_doors()
    c = costmap_of(m)
    robot = (3.0, 3.0)
    everything = rank_frontiers(m, c, robot, min_frontier_size=0.5)
    assert len(everything) >= 8
    for enough in (1, 3, 5):
        stats = {}
        best = rank_frontiers(m, c, robot, min_frontier_size=0.5, enough=enough, stats=stats)
        assert [(f.goal, f.cost) for f in best[:enough]] == [(f.goal, f.cost) for f in everything[:enough]]
        assert len(best) + len(stats['unranked']) == len(everything)
        assert len(stats['unranked']) > 0  # the far ones were left
    # the frontier of the goal being driven to is ranked however far it is
    far = everything[-1]
    stats = {}
    best = rank_frontiers(m, c, robot, min_frontier_size=0.5, enough=1, keep_goal=far.goal, stats=stats)
    assert far.goal in [f.goal for f in best]
    # those that may not be sent do not count towards `enough`
    not_first = rank_frontiers(m, c, robot, min_frontier_size=0.5, enough=1,
                               eligible=lambda f: f.goal != everything[0].goal)
    assert [f.goal for f in not_first[:2]] == [f.goal for f in everything[:2]]


def test_a_map_allocated_larger_than_what_is_known_gives_the_same_frontiers():
    # SLAM allocates its map beyond what the robot has seen; the search is cut to the known part
    m = room(door=(1.0, 2.0))
    big = Grid(np.pad(m.data, ((100, 300), (200, 40)), constant_values=-1), RES, (-200 * RES, -100 * RES))
    a = rank_frontiers(m, costmap_of(m), (2.0, 2.0), min_frontier_size=0.5)
    stats = {}
    b = rank_frontiers(big, costmap_of(big), (2.0, 2.0), min_frontier_size=0.5, stats=stats)
    assert [(f.goal, f.cost, f.unknown_m2) for f in a] == [(pytest.approx(f.goal), pytest.approx(f.cost),
                                                            pytest.approx(f.unknown_m2)) for f in b]
    assert stats['costmap'].data.shape[0] < big.data.shape[0] and stats['costmap'].data.shape[1] < big.data.shape[1]


def test_a_boundary_leaves_the_frontiers_outside_it_out_and_counts_them():
    m = _hall_with_doors()
    c = costmap_of(m)
    everything = rank_frontiers(m, c, (3.0, 3.0), min_frontier_size=0.5)
    # the western half of the hall (x < 12 m), walls included
    west = np.array([[1.0, 1.0], [12.0, 1.0], [12.0, 15.0], [1.0, 15.0]])
    stats = {}
    inside = rank_frontiers(m, c, (3.0, 3.0), min_frontier_size=0.5, boundary=west, stats=stats)
    assert inside and all(f.cells[:, 0].max() < 12.0 for f in inside)
    assert len(inside) < len(everything)
    left_out = sum(f.size_m for f in everything if f.cells[:, 0].min() > 12.0)
    assert stats['outside_m'] == pytest.approx(left_out, abs=0.2)
    # nothing inside: nothing to explore there
    assert rank_frontiers(m, c, (3.0, 3.0), boundary=np.array([[3.0, 3.0], [4.0, 3.0], [4.0, 4.0]])) == []


def test_the_boundary_parameter_is_checked_by_name():
    from mbot_slam_navigation.nav.explore import polygon_of
    from mbot_slam_navigation.nav.params import ParamError
    assert polygon_of([], '/explore/boundary') is None
    assert polygon_of([[0, 0], [1, 0], [1, 1]], '/explore/boundary').shape == (3, 2)
    for bad in ([[0, 0], [1, 0]], [[0, 0], [1], [1, 1]], [[0, 0], [1, 'a'], [1, 1]], 'square'):
        with pytest.raises(ParamError, match='/explore/boundary must be a list of at least 3'):
            polygon_of(bad, '/explore/boundary')


def test_a_keepout_zone_makes_no_frontier_and_counts_what_it_took():
    """A room with its door open onto unknown space: a keep-out mask over the space beyond the door
    leaves no frontier (it is excluded, not unreachable), and stats['keepout_m'] counts the door."""
    m = room(door=(1.0, 2.0))
    c = costmap_of(m)
    assert rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.5)  # the door's frontier
    # the mask: its own grid (another origin), forbidden east of the room's east wall (x >= 5.05 m)
    mask = np.zeros((160, 220), np.int8)  # 11 m x 8 m from (-1, -1)
    mask[:, int(round((5.05 + 1.0) / RES)):] = 100
    keepout = Grid(mask, RES, (-1.0, -1.0))
    stats, unreachable = {}, []
    assert rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.5, keepout=keepout, stats=stats,
                          unreachable=unreachable) == []
    assert unreachable == []
    assert stats['keepout_m'] == pytest.approx(1.0, abs=0.15)  # the 1 m door
    # a zone elsewhere takes nothing away
    far = Grid(np.full((10, 10), 100, np.int8), RES, (0.0, 5.0))
    stats = {}
    assert rank_frontiers(m, c, (2.0, 2.0), min_frontier_size=0.5, keepout=far, stats=stats)
    assert stats['keepout_m'] == 0.0


def test_a_followed_map_patches_a_copy_and_keeps_what_does_not_fit_for_the_next_whole_map():
    from types import SimpleNamespace
    import rospy
    from mbot_slam_navigation.maps.updates import FollowedMap

    def whole(grid, t):
        return SimpleNamespace(data=grid.data.ravel(), header=SimpleNamespace(stamp=rospy.Time(t)), info=SimpleNamespace(
            width=grid.data.shape[1], height=grid.data.shape[0], resolution=grid.resolution,
            origin=SimpleNamespace(position=SimpleNamespace(x=grid.origin[0], y=grid.origin[1]))))

    def update(x, y, w, h, value, t):
        return SimpleNamespace(x=x, y=y, width=w, height=h, data=[value] * (w * h),
                               header=SimpleNamespace(stamp=rospy.Time(t)))

    m, f = room(), FollowedMap()
    assert f.update(update(10, 20, 3, 2, 100, 1)) is None  # no whole map yet
    held = f.whole(whole(m, 2), rospy.Time(2))
    assert (held.data == m.data).all()  # the update older than the map is not applied again
    p = f.update(update(10, 20, 3, 2, 100, 3))
    assert (p.data[20:22, 10:13] == 100).all() and held.data[20, 10] != 100  # the old grid is untouched
    assert p.origin == m.origin and p.resolution == m.resolution
    # the map grows: its update overtakes it, does not fit the map held, and is written into it when it comes
    assert f.update(update(159, 0, 3, 1, 100, 5)) is None
    grown = Grid(np.pad(m.data, ((0, 0), (0, 10)), constant_values=-1), m.resolution, m.origin)
    g = f.whole(whole(grown, 4), rospy.Time(5))
    assert g.data.shape == grown.data.shape and (g.data[0, 159:162] == 100).all()
    # a stale latched map (older than the one held, the clock not gone back) leaves it as it is
    assert f.whole(whole(m, 1), rospy.Time(6)) is g and f.stamp == rospy.Time(4)
