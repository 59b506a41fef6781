"""Costmap filters, ROS-free (the C++ the roscpp move_base runs, through the binding): keep-out zones
from a mask or from polygons, speed zones, and the errors a bad filter gives."""
import numpy as np
import pytest

from mbot_slam_navigation import _core

FREE, INSCRIBED, LETHAL, UNKNOWN = 0, 253, 254, 255
KEEPOUT = {'name': 'keepout_filter', 'type': 'nav2_costmap_2d::KeepoutFilter'}
SPEED = {'name': 'speed_filter', 'type': 'nav2_costmap_2d::SpeedFilter'}
PROHIBITION = {'name': 'prohibition', 'type': 'costmap_prohibition_layer_namespace::CostmapProhibitionLayer'}


def config(extra, warnings=None):
    """The tutorial's global costmap (pre-Hydro keys: static map, inflation 0.6 m) with `extra`."""
    values = {'static_map': True, 'robot_radius': 0.2, 'inflation_radius': 0.6, 'cost_scaling_factor': 10.0,
              'observation_sources': 'scan', 'scan': {'data_type': 'LaserScan'}}
    values.update(extra)
    return _core.read_costmap_config('global_costmap', values, (warnings.append if warnings is not None else None),
                                     '/move_base')


def at(lc, x, y):
    m = lc.master()
    return int(m.costs()[int(np.floor((y - m.origin[1]) / m.resolution)), int(np.floor((x - m.origin[0]) / m.resolution))])


def room_mask(value=100, n=100, box=(40, 60, 40, 60)):
    """An n x n mask at 0.05 m, origin (0, 0), `value` inside rows/cols box (a 1 m square at (2..3, 2..3))."""
    mask = np.zeros((n, n), np.int8)
    r0, r1, c0, c1 = box
    mask[r0:r1, c0:c1] = value
    return mask


def test_keepout_mask_is_lethal_and_inflated_as_a_wall_and_named():
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT]}), print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    lc.set_filter_mask(0, room_mask(), (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == LETHAL
    assert at(lc, 1.9, 2.5) == INSCRIBED   # within the robot's radius of the zone: the footprint would enter
    assert 0 < at(lc, 1.6, 2.5) < INSCRIBED
    assert at(lc, 0.5, 0.5) == FREE
    assert lc.keepout_zone_at((2.5, 2.5)) == '#1 at (2.5, 2.5) (filter keepout_filter)'
    assert lc.keepout_zone_at((1.0, 1.0)) == ''


def test_keepout_over_unknown_cells_and_grey_mask_values():
    """Unknown map cells become lethal under a zone (exploration keeps out of a room it has not seen);
    mask values between 1 and 99 raise the cost in proportion, below the inscribed cost."""
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT], 'inflation_radius': 0.0, 'track_unknown_space': True}), print)
    lc.set_map(np.full((100, 100), -1, np.int8), (0.0, 0.0), 0.05)
    mask = room_mask()
    mask[10:20, 10:20] = 50
    lc.set_filter_mask(0, mask, (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == LETHAL
    assert 100 < at(lc, 0.7, 0.7) < INSCRIBED  # 50 of 100
    assert lc.keepout_zone_at((0.7, 0.7)) == ''  # not forbidden: the goal may be sent there
    assert at(lc, 4.0, 4.0) == UNKNOWN


def test_mask_of_another_resolution_is_refused_with_both_figures():
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT]}), print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    with pytest.raises(ValueError, match='0.1 m, the costmap.s 0.05 m'):
        lc.set_filter_mask(0, room_mask(n=50, box=(20, 30, 20, 30)), (0.0, 0.0), 0.1)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == FREE  # the costmap goes on without the filter


def test_a_new_map_of_another_resolution_drops_the_mask_and_says_so():
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT]}), print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    lc.set_filter_mask(0, room_mask(), (0.0, 0.0), 0.05)
    lc.set_map(np.zeros((50, 50), np.int8), (0.0, 0.0), 0.1)
    errors = lc.take_filter_errors()
    assert len(errors) == 1 and errors[0].startswith('keepout_filter: the map has a resolution of 0.1 m')
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == FREE and lc.keepout_zone_at((2.5, 2.5)) == ''


def test_the_mask_follows_world_coordinates_as_slam_grows_the_map():
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT], 'inflation_radius': 0.0}), print)
    lc.set_filter_mask(0, room_mask(), (0.0, 0.0), 0.05)  # before the first map: accepted
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == LETHAL
    lc.set_map(np.zeros((140, 160), np.int8), (-3.0, -2.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 2.5, 2.5) == LETHAL and at(lc, 1.9, 2.5) == FREE and at(lc, 3.05, 2.5) == FREE


def test_rolling_window_sees_the_zone_where_it_lies():
    values = {'static_map': False, 'rolling_window': True, 'width': 3.0, 'height': 3.0, 'robot_radius': 0.2,
              'inflation_radius': 0.0, 'observation_sources': 'scan', 'scan': {'data_type': 'LaserScan'},
              'filters': [KEEPOUT]}
    lc = _core.LayeredCostmap(_core.read_costmap_config('local_costmap', values, None), print)
    lc.set_filter_mask(0, room_mask(), (0.0, 0.0), 0.05)
    lc.update((1.5, 2.5, 0.0))
    assert at(lc, 2.2, 2.5) == LETHAL and at(lc, 1.5, 2.5) == FREE
    lc.update((3.5, 2.5, 0.0))
    assert at(lc, 2.9, 2.5) == LETHAL and at(lc, 3.2, 2.5) == FREE


def test_prohibition_areas_polygons_with_names_and_in_the_plugins_list():
    values = {'plugins': [{'name': 'static_layer', 'type': 'costmap_2d::StaticLayer'}, PROHIBITION,
                          {'name': 'inflation_layer', 'type': 'costmap_2d::InflationLayer'}],
              'robot_radius': 0.2, 'inflation_layer': {'inflation_radius': 0.0},
              'prohibition': {'prohibition_areas': [[[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]],
                                                    {'name': 'server room', 'points': [[3, 3], [4, 3], [4, 4]]}]}}
    cfg = _core.read_costmap_config('global_costmap', values, None, '/move_base')
    assert [f.kind for f in cfg.filters] == ['keepout'] and cfg.filters[0].error == ''
    lc = _core.LayeredCostmap(cfg, print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert at(lc, 1.5, 1.5) == LETHAL and at(lc, 0.8, 1.5) == FREE
    assert lc.keepout_zone_at((1.5, 1.5)).startswith('/move_base/global_costmap/prohibition/prohibition_areas[0]')
    assert lc.keepout_zone_at((3.8, 3.2)) == "'server room' (filter prohibition)"


@pytest.mark.parametrize('areas, why', [
    ([[[0, 0], [1, 0]]], r'prohibition_areas\[0\]: a zone.s polygon needs at least 3 points, it has 2'),
    ([[[0, 0], [1, 0], 'x']], r'prohibition_areas\[0\]'),
    ('a string', 'must be a list of polygons'),
])
def test_a_bad_polygon_names_its_key_and_the_filter_is_left_out(areas, why):
    cfg = config({'filters': [PROHIBITION], 'prohibition': {'prohibition_areas': areas}})
    assert len(cfg.filters) == 1
    import re
    assert re.search(why, cfg.filters[0].error), cfg.filters[0].error
    lc = _core.LayeredCostmap(cfg, print)
    lc.set_map(np.zeros((40, 40), np.int8), (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert lc.master().costs().max() == FREE


def test_filters_list_accepts_nav2_names_and_rejects_other_types():
    values = {'filters': ['keepout_filter'], 'keepout_filter': {'plugin': 'nav2_costmap_2d::KeepoutFilter',
                                                               'mask_topic': '/zones'}}
    cfg = config(values)
    assert cfg.filters[0].mask_topic == '/zones' and cfg.filters[0].error == ''
    with pytest.raises(ValueError, match=r'filters\[0\]: "costmap_2d::StaticLayer" is not a filter'):
        config({'filters': [{'name': 's', 'type': 'costmap_2d::StaticLayer'}]})


def test_speed_limit_is_the_lowest_under_the_footprint():
    lc = _core.LayeredCostmap(config({'filters': [SPEED]}), print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    mask = room_mask(value=30)
    mask[50:60, 40:60] = 60
    lc.set_filter_mask(0, mask, (0.0, 0.0), 0.05)
    lc.update((0.5, 0.5, 0.0))
    assert lc.speed_limit_at((0.5, 0.5, 0.0)) is None
    assert lc.speed_limit_at((1.85, 2.2, 0.0))[:2] == (30.0, True)  # the footprint's edge reaches in
    limit, percent, zone = lc.speed_limit_at((2.5, 2.5, 0.0))
    assert (limit, percent) == (30.0, True) and zone.endswith('(filter speed_filter)')
    assert lc.speed_limit_at((2.5, 2.8, 0.0))[0] == 60.0
    assert at(lc, 2.5, 2.5) == FREE  # a speed zone costs nothing


def test_a_zones_cell_the_laser_marks_stays_whole():
    """Something the laser sees just inside a keep-out zone does not shrink the zone's cell to the
    box of its returns: a footprint reaching into that cell, short of the returns, is in the zone."""
    lc = _core.LayeredCostmap(config({'filters': [KEEPOUT]}), print)
    lc.set_map(np.zeros((100, 100), np.int8), (0.0, 0.0), 0.05)
    lc.set_filter_mask(0, room_mask(), (0.0, 0.0), 0.05)  # the zone: x and y in [2, 3)
    pose = (1.0, 2.525, 0.0)
    lc.add_scan('scan', 1.0, pose, 0.1, 0.0, 0.1, 0.1, 6.0, [1.04])  # a return at (2.04, 2.525)
    lc.update(pose)
    m = lc.master()
    assert at(lc, 2.04, 2.525) == LETHAL
    # A thin footprint from x 1.80 to 2.02 along y = 2.525: 2 cm into the zone's first column.
    footprint = [(-0.1, -0.01), (-0.1, 0.01), (0.12, 0.01), (0.12, -0.01)]
    assert m.footprint_cost((1.9, 2.525, 0.0), footprint) < 0
