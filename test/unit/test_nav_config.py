"""move_base configuration and costmap composition, ROS-free: the tutorial YAMLs as rosparam loads them.

The configuration and the layered costmap are the C++ the roscpp move_base runs (through the
binding); these tests were the rospy move_base's and pass unchanged in substance."""
import math
import os

import numpy as np
import pytest
import yaml

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.params import ParamError, ParamReader

FREE, INSCRIBED, LETHAL, UNKNOWN = 0, 253, 254, 255

CONFIG = os.path.join(os.path.dirname(__file__), '..', '..', 'config')


def load(name):
    with open(os.path.join(CONFIG, name)) as f:
        return yaml.safe_load(f)


def CostmapConfig(name, values, warn, ns_prefix=''):
    return _core.read_costmap_config(name, values, warn, ns_prefix)


def LayeredCostmap(config, warn):
    return _core.LayeredCostmap(config, warn)


def costs_of(lc):
    m = lc.master()
    return m.costs()


def cell_of(lc, x, y):
    m = lc.master()
    return (int(np.floor((x - m.origin[0]) / m.resolution)), int(np.floor((y - m.origin[1]) / m.resolution)))


def tutorial_costmap(which, common='costmap_common_params.yaml'):
    """The dict /move_base/<which> holds after the tutorial launch file's rosparam loads."""
    values = dict(load(common))
    values.update(load('%s_params.yaml' % which)[which])
    return values


def test_tutorial_local_costmap_warns_about_each_misplaced_or_misspelt_key():
    warnings = []
    cfg = CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), warnings.append, '/move_base')
    text = '\n'.join(warnings)
    assert 'tranform_tolerance (did you mean transform_tolerance?)' in text
    assert 'planner_patiente (did you mean planner_patience? that is a parameter of move_base' in text
    assert 'planner_frequency has no effect here: planner_frequency is a parameter of move_base' in text
    # Frames lose their leading '/', with one warning each.
    assert cfg.global_frame == 'map' and cfg.robot_base_frame == 'base_footprint'
    assert sum('leading "/"' in w for w in warnings) == 2
    assert cfg.rolling_window and cfg.static is None
    assert cfg.transform_tolerance == 0.3  # the misspelt key is not taken
    assert cfg.publish_frequency == 1.0
    assert [kind for _, kind in cfg.layers] == ['obstacle', 'inflation']


def test_tutorial_global_costmap_has_static_obstacle_and_inflation_layers():
    cfg = CostmapConfig('global_costmap', tutorial_costmap('global_costmap'), lambda w: None, '/move_base')
    assert [kind for _, kind in cfg.layers] == ['static', 'obstacle', 'inflation']
    scan = cfg.obstacle.sources['scan']
    assert (scan.topic, scan.sensor_frame, scan.marking, scan.clearing) == ('/scan', 'hokuyo_link', True, True)
    assert scan.obstacle_range == 2.5 and scan.raytrace_range == 3.0 and scan.max_obstacle_height == 0.4
    assert cfg.inflation.inflation_radius == 0.6 and cfg.inflation.cost_scaling_factor == 10.0
    # The car's 0.4 m square padded by the default 0.01 m: inscribed 0.2 + 0.01 / sqrt(2) along the diagonal.
    assert cfg.inscribed_radius == pytest.approx(0.2 + 0.01 / math.sqrt(2), abs=1e-6)
    assert cfg.circumscribed_radius == pytest.approx(0.2 * math.sqrt(2) + 0.01, abs=1e-6)


def test_mbot_common_params_give_a_round_footprint():
    cfg = CostmapConfig('global_costmap', tutorial_costmap('global_costmap', 'mbot/costmap_common_params.yaml'),
                        lambda w: None)
    # A 16-gon touching the 0.2 m circle, its corners pushed out 0.01 m: edges at 0.2 + 0.01 cos(pi / 16).
    assert cfg.inscribed_radius == pytest.approx(0.2 + 0.01 * math.cos(math.pi / 16), abs=1e-6)
    assert cfg.obstacle.sources['scan'].sensor_frame == 'laser_link'


def test_plugins_style_reads_each_layers_namespace():
    values = {'global_frame': 'odom', 'robot_radius': 0.3,
              'plugins': [{'name': 'static', 'type': 'costmap_2d::StaticLayer'},
                          {'name': 'obstacles', 'type': 'costmap_2d::VoxelLayer'},
                          {'name': 'inflater', 'type': 'costmap_2d::InflationLayer'}],
              'static': {'map_topic': '/slam_map', 'track_unknown_space': False},
              'obstacles': {'observation_sources': 'front', 'obstacle_range': 4.0,
                            'front': {'data_type': 'LaserScan', 'topic': 'front_scan', 'clearing': True}},
              'inflater': {'inflation_radius': 0.9, 'cost_scaling_factor': 3.0}}
    warnings = []
    cfg = CostmapConfig('c', values, warnings.append)
    assert warnings == []
    assert cfg.static.map_topic == '/slam_map' and not cfg.static.track_unknown_space
    assert cfg.obstacle.sources['front'].obstacle_range == 4.0  # the layer's value is the source default
    assert cfg.inflation.inflation_radius == 0.9


def test_unknown_layer_type_names_the_nearest_one():
    values = {'plugins': [{'name': 'obstacles', 'type': 'costmal_2d::ObstacleLayer'}]}
    with pytest.raises(ParamError, match=r'unknown layer type "costmal_2d::ObstacleLayer" \(did you mean costmap_2d::ObstacleLayer\?\)'):
        CostmapConfig('local_costmap', values, lambda w: None)


def test_bad_values_name_the_key_and_namespace():
    with pytest.raises(ParamError, match=r'/move_base/local_costmap/resolution must be positive'):
        CostmapConfig('local_costmap', {'resolution': 0}, lambda w: None, '/move_base')
    with pytest.raises(ParamError, match=r'/c/inflation_radius must be a number'):
        CostmapConfig('c', {'inflation_radius': 'wide'}, lambda w: None)
    with pytest.raises(ParamError, match=r'footprint.*does not contain the robot'):
        CostmapConfig('c', {'footprint': [[1, 1], [2, 1], [2, 2]]}, lambda w: None)
    with pytest.raises(ParamError, match=r'observation source "laser".*/c/laser is not a dict'):
        CostmapConfig('c', {'observation_sources': 'laser'}, lambda w: None)


def test_tutorial_local_planner_params_take_ros_effective_values():
    warnings = []
    p, ros = _core.read_local_planner_params(load('base_local_planner_params.yaml')['TrajectoryPlannerROS'],
                                             '/move_base/TrajectoryPlannerROS', warnings.append, 10.0)
    assert (p.max_vel_x, p.min_vel_x, p.max_vel_theta, p.min_vel_theta) == (0.3, 0.05, 1.0, -1.0)
    assert p.min_in_place_vel_theta == 0.5  # the new name wins over min_in_place_rotational_vel: 0.01
    assert (p.path_distance_bias, p.goal_distance_bias) == (0.8, 0.4)  # from pdist_scale / gdist_scale
    assert p.meter_scoring and not p.holonomic_robot and not p.dwa
    assert p.sim_period == pytest.approx(1 / 3.0)  # the namespace's controller_frequency wins, as searchParam
    assert (p.sim_time, p.vx_samples, p.vtheta_samples) == (1.7, 20, 20)  # dynamic_reconfigure defaults
    assert ros.xy_goal_tolerance == 0.1 and ros.yaw_goal_tolerance == 0.1
    text = '\n'.join(warnings)
    assert 'pdist_scale is deprecated' in text and 'max_rotational_vel has no effect' in text


def test_static_layer_values_follow_costmap_2d():
    params = _core.StaticLayerConfig()
    assert [_core.static_cost(v, params) for v in (-1, 0, 50, 99, 100)] == [UNKNOWN, FREE, FREE, FREE, LETHAL]
    params.track_unknown_space = False
    assert _core.static_cost(-1, params) == FREE


def test_obstacles_raise_the_map_but_unknown_obstacle_cells_do_not():
    """costmap_2d's updateWithMax: a known obstacle-layer cell raises the master, an unknown one keeps it."""
    values = {'static_map': True, 'robot_radius': 0.05, 'inflation_radius': 0.0, 'track_unknown_space': True,
              'observation_sources': 'scan', 'scan': {'data_type': 'LaserScan', 'clearing': True, 'marking': True}}
    lc = LayeredCostmap(CostmapConfig('c', values, lambda w: None), print)
    data = np.zeros((20, 20), np.int8)
    data[10, 15] = -1
    lc.set_map(data, (0.0, 0.0), 0.05)
    lc.update((0.1, 0.1, 0.0))
    costs = costs_of(lc)
    assert costs[10, 15] == UNKNOWN and costs[5, 5] == FREE  # the obstacle layer is unknown there: the map stays
    lc.add_scan('scan', 1.0, (0.1, 0.525, 0.0), 0.1, 0.0, 0.1, 0.01, 6.0, [0.6])  # a hit at (0.7, 0.525): cell (14, 10)
    lc.update((0.1, 0.1, 0.0))
    assert costs_of(lc)[10, 14] == LETHAL and costs_of(lc)[10, 15] == UNKNOWN


def test_layered_costmap_marks_clears_and_inflates_and_follows_a_growing_map():
    values = dict(tutorial_costmap('global_costmap'))
    cfg = CostmapConfig('global_costmap', values, lambda w: None)
    lc = LayeredCostmap(cfg, print)
    assert not lc.ready
    lc.set_map(np.zeros((40, 40), np.int8), (0.0, 0.0), 0.05)
    # A scan from (0.5, 1.0) facing +x with one beam hitting at 1.0 m: (1.5, 1.0) is lethal, inflated around.
    assert lc.add_scan('scan', 1.0, (0.5, 1.0, 0.0), 0.2, 0.0, 0.1, 0.1, 6.0, [1.0])
    lc.update((0.5, 1.0, 0.0))
    costs = costs_of(lc)
    hit = cell_of(lc, 1.5, 1.0)
    assert costs[hit[1], hit[0]] == LETHAL
    near = cell_of(lc, 1.35, 1.0)
    assert costs[near[1], near[0]] == INSCRIBED
    # SLAM grows the map to the left: the mark keeps its world position.
    lc.set_map(np.zeros((40, 60), np.int8), (-1.0, 0.0), 0.05)
    lc.update((0.5, 1.0, 0.0))
    costs = costs_of(lc)
    hit = cell_of(lc, 1.5, 1.0)
    assert costs.shape == (40, 60) and costs[hit[1], hit[0]] == LETHAL
    # The obstacle moved away: the beam now returns nothing (+inf) and clears the cell.
    lc.add_scan('scan', 2.0, (0.5, 1.0, 0.0), 0.2, 0.0, 0.1, 0.1, 6.0, [float('inf')])
    lc.update((0.5, 1.0, 0.0))
    assert costs_of(lc)[hit[1], hit[0]] == FREE


def test_footprint_clearing_keeps_a_return_outside_the_footprint_under_its_outline():
    """A post 5 mm beside the padded footprint (0.21 m) lies in a cell the outline passes through:
    costmap_2d's footprint clearing wipes it, and the robot would not see what stands beside it. Its
    return lies outside the footprint, so it stays; a return inside the footprint (the robot's own
    body) is cleared."""
    lc = LayeredCostmap(CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), lambda w: None), print)
    pose = (2.0, 1.0, 0.0)
    lc.update(pose)
    # Beams to the left (+y) and to the right (-y): 0.215 m (outside) and 0.15 m (inside).
    lc.add_scan('scan', 1.0, pose, 0.1, -np.pi / 2, np.pi, 0.1, 6.0, [0.15, 0.215])
    lc.update(pose)
    costs = costs_of(lc)
    outside, inside = cell_of(lc, 2.0, 1.215), cell_of(lc, 2.0, 0.85)
    assert outside[1] == cell_of(lc, 2.0, 1.21)[1]  # the outline (y = 1.21) passes through its cell
    assert costs[outside[1], outside[0]] == LETHAL
    assert costs[inside[1], inside[0]] != LETHAL


def test_bounded_updates_equal_a_full_recomputation():
    """Each update redoes only the window that changed; the grid is the one a full recomputation gives."""
    cfg = CostmapConfig('global_costmap', tutorial_costmap('global_costmap'), lambda w: None)
    rng = np.random.default_rng(3)
    data = np.zeros((200, 200), np.int8)
    data[rng.integers(0, 200, 300), rng.integers(0, 200, 300)] = 100
    lc = LayeredCostmap(cfg, print)
    lc.set_map(data, (0.0, 0.0), 0.05)
    lc.update((5.0, 5.0, 0.0))
    for step in range(6):
        pose = (2.0 + step, 5.0, 0.3 * step)
        ranges = list(rng.uniform(0.3, 4.0, 36))
        lc.add_scan('scan', 1.0 + step, pose, 0.2, -3.1, 0.17, 0.1, 6.0, ranges)
        if step == 3:  # the map changes in one place, as SLAM's does
            data[100:104, 20:30] = 100
            lc.set_map(data, (0.0, 0.0), 0.05)
        x0, y0, x1, y1 = lc.update(pose)
        assert 0 < (x1 - x0) * (y1 - y0) < 200 * 200  # a window, not the whole grid
        fresh = LayeredCostmap(cfg, print)
        fresh.set_map(data, (0.0, 0.0), 0.05)
        # The same obstacle layer, then one full update.
        fresh_master = costs_of(lc)
        lc.reset_obstacles((pose[0], pose[1], 1000.0))  # keeps everything: forces a full recomposition
        lc.update(pose)
        assert np.array_equal(costs_of(lc), fresh_master), 'step %d' % step


def test_a_sensor_above_max_obstacle_height_is_reported_once():
    warnings = []
    lc = LayeredCostmap(CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), lambda w: None), warnings.append)
    for _ in range(3):
        assert not lc.add_scan('scan', 1.0, (0, 0, 0), 0.5, 0.0, 0.1, 0.1, 6.0, [1.0])
    assert len(warnings) == 1 and 'max_obstacle_height 0.400' in warnings[0]


def test_rolling_window_follows_the_robot():
    lc = LayeredCostmap(CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), lambda w: None), print)
    lc.update((10.0, -3.0, 0.0))
    m = lc.master()
    assert (m.height, m.width) == (100, 100)
    assert m.origin[0] == pytest.approx(7.5) and m.origin[1] == pytest.approx(-5.5)


def test_prune_plan_drops_what_the_robot_passed():
    plan = [np.array([x, 0.0]) for x in np.arange(0, 5, 0.5)]
    assert _core.prune_plan(plan, np.array([2.4, 0.0, 0.0]))[0][0] == pytest.approx(1.5)


def test_move_base_parameters_and_recoveries():
    warnings = []
    values = {'controller_frequency': 10.0, 'controller_patiente': 15.0, 'base_global_planner': 'navfn/NavfnROS',
              'NavfnROS': {'use_astar': True}, 'conservative_reset': {'reset_distance': 2.0},
              'TrajectoryPlannerROS': load('base_local_planner_params.yaml')['TrajectoryPlannerROS']}
    c = _core.read_move_base_config(values, '/move_base', warnings.append, 0.25)
    assert c.use_astar and c.global_ns == 'NavfnROS' and c.local_ns == 'TrajectoryPlannerROS'
    assert [r.name for r in c.recoveries] == ['conservative_reset', 'rotate_recovery', 'back_up', 'aggressive_reset',
                                              'rotate_recovery']
    assert c.recoveries[0].reset_distance == 2.0 and c.recoveries[3].reset_distance == pytest.approx(1.0)
    assert any('controller_patiente (did you mean controller_patience?)' in w for w in warnings)
    with pytest.raises(ParamError, match=r'unknown planner "navfn/NavFnROS" \(did you mean navfn/NavfnROS\?\)'):
        _core.read_move_base_config({'base_global_planner': 'navfn/NavFnROS'}, '/move_base', None, 0.25)
    assert c.lethal_cost == 0, 'the global costmap contact cost unless set'
    assert _core.read_move_base_config({'NavfnROS': {'lethal_cost': 253}}, '/move_base', None, 0.25).lethal_cost == 253
    with pytest.raises(ParamError, match=r'/move_base/GlobalPlanner/lethal_cost must be in 0..253, got 300'):
        _core.read_move_base_config({'base_global_planner': 'global_planner/GlobalPlanner', 'GlobalPlanner': {'lethal_cost': 300}},
                                    '/move_base', None, 0.25)
    with pytest.raises(ParamError, match=r'unknown recovery type "rotate_recovery/RotateRecovry"'):
        _core.read_move_base_config({'recovery_behaviors': [{'name': 'r', 'type': 'rotate_recovery/RotateRecovry'}]},
                                    '/move_base', None, 0.25)


def test_param_reader_types():
    r = ParamReader({'a': True, 'b': '1'}, '/ns', lambda w: None)
    with pytest.raises(ParamError, match='/ns/a must be a number'):
        r.number('a', 0.0)
    with pytest.raises(ParamError, match='/ns/b must be true or false'):
        r.boolean('b', False)


def test_a_source_is_current_while_its_scans_keep_coming_and_stale_after_expected_update_rate():
    """costmap_2d's isCurrent: a scan already applied still counts as the source's newest."""
    values = {'static_map': False, 'robot_radius': 0.2, 'observation_sources': 'scan',
              'scan': {'data_type': 'LaserScan', 'expected_update_rate': 0.5, 'clearing': True, 'marking': True}}
    lc = LayeredCostmap(CostmapConfig('c', values, lambda w: None), print)
    assert lc.stale_sources(1.0) == ['scan (topic scan): no data yet']
    assert lc.add_scan('scan', 1.0, (0.5, 0.5, 0.0), 0.1, 0.0, 0.1, 0.1, 6.0, [1.0])
    lc.update((0.5, 0.5, 0.0))
    lc.update((0.5, 0.5, 0.0))
    assert lc.stale_sources(1.4) == []
    assert lc.stale_sources(1.6) == ['scan (topic scan): no data for 0.60 s, expected every 0.50 s (expected_update_rate)']


def test_a_source_without_expected_update_rate_goes_stale_after_two_seconds_and_an_explicit_zero_never():
    """costmap_2d's default (0: never stale) lets a silent laser leave the robot driving blind."""
    for rate, stale_at_3 in ((None, True), (0.0, False)):
        scan = {'data_type': 'LaserScan', 'clearing': True, 'marking': True}
        if rate is not None:
            scan['expected_update_rate'] = rate
        lc = LayeredCostmap(CostmapConfig('c', {'static_map': False, 'robot_radius': 0.2, 'observation_sources': 'scan',
                                                'scan': scan}, lambda w: None), print)
        assert lc.add_scan('scan', 1.0, (0.5, 0.5, 0.0), 0.1, 0.0, 0.1, 0.1, 6.0, [1.0])
        assert lc.stale_sources(2.9) == []
        assert bool(lc.stale_sources(3.1)) == stale_at_3


def test_a_laser_covered_by_a_person_is_marked_inside_the_footprint_that_clearing_would_wipe():
    # A person walked into the robot and covers its laser: every beam -inf (REP 117). The marks at
    # range_min lie inside the footprint, which footprint clearing empties after each scan (the
    # robot's own body is no obstacle); these stay, so the robot does not drive on into the person.
    # Returns beyond them clear them again. too_close_is_obstacle false is costmap_2d's way.
    for too_close, expect in ((True, LETHAL), (False, FREE)):
        values = {'static_map': False, 'robot_radius': 0.2, 'width': 3.0, 'height': 3.0, 'observation_sources': 'scan',
                  'scan': {'data_type': 'LaserScan', 'clearing': True, 'marking': True,
                           'too_close_is_obstacle': too_close}}
        lc = LayeredCostmap(CostmapConfig('c', values, lambda w: None), print)
        pose = (1.5, 1.5, 0.0)
        ranges = [float('-inf')] * 36
        assert lc.add_scan('scan', 1.0, pose, 0.1, -math.pi, 2 * math.pi / 36, 0.1, 6.0, ranges)
        lc.update(pose)
        ahead = cell_of(lc, 1.6, 1.5)
        assert costs_of(lc)[ahead[1], ahead[0]] == expect, too_close
        lc.add_scan('scan', 2.0, pose, 0.1, -math.pi, 2 * math.pi / 36, 0.1, 6.0, [1.0] * 36)
        lc.update(pose)
        assert costs_of(lc)[ahead[1], ahead[0]] == FREE


def test_map_updates_patch_the_static_layer_as_a_whole_map_would():
    """subscribe_to_updates: a window of the map replaced gives the costmap a whole new map gives;
    an update that does not fit the map held changes nothing."""
    values = dict(tutorial_costmap('global_costmap'))
    base = np.zeros((60, 80), np.int8)
    base[30, :] = 100
    patched = LayeredCostmap(CostmapConfig('global_costmap', values, lambda w: None), print)
    whole = LayeredCostmap(CostmapConfig('global_costmap', values, lambda w: None), print)
    patched.set_map(base, (0.0, 0.0), 0.05)
    patched.update((0.5, 0.5, 0.0))
    after = base.copy()
    after[10:20, 40:50] = 100
    after[30, 5:15] = 0  # a door opened in the wall
    window = after[10:31, 5:50]
    assert patched.patch_map(window, 5, 10)
    patched.update((0.5, 0.5, 0.0))
    whole.set_map(after, (0.0, 0.0), 0.05)
    whole.update((0.5, 0.5, 0.0))
    assert np.array_equal(costs_of(patched), costs_of(whole))
    assert not patched.patch_map(np.zeros((5, 5), np.int8), 78, 0)  # past the map's edge
