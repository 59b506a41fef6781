"""move_base configuration and costmap composition, ROS-free: the tutorial YAMLs as rosparam loads them."""
import math
import os

import numpy as np
import pytest
import yaml

from mbot_slam_navigation.nav.costmap import (FREE, INSCRIBED, LETHAL, UNKNOWN, CostmapConfig, LayeredCostmap,
                                              combine_max, static_costs)
from mbot_slam_navigation.nav.params import ParamError, ParamReader
from mbot_slam_navigation.nav.trajectory_planner import local_planner_params, prune_plan

CONFIG = os.path.join(os.path.dirname(__file__), '..', '..', 'config')


def load(name):
    with open(os.path.join(CONFIG, name)) as f:
        return yaml.safe_load(f)


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
    assert [kind for _, kind, _ in cfg.layers] == ['obstacle', 'inflation']


def test_tutorial_global_costmap_has_static_obstacle_and_inflation_layers():
    cfg = CostmapConfig('global_costmap', tutorial_costmap('global_costmap'), lambda w: None, '/move_base')
    assert [kind for _, kind, _ in cfg.layers] == ['static', 'obstacle', 'inflation']
    scan = cfg.obstacle['sources']['scan']
    assert (scan.topic, scan.sensor_frame, scan.marking, scan.clearing) == ('/scan', 'hokuyo_link', True, True)
    assert scan.obstacle_range == 2.5 and scan.raytrace_range == 3.0 and scan.max_obstacle_height == 0.4
    assert cfg.inflation['inflation_radius'] == 0.6 and cfg.inflation['cost_scaling_factor'] == 10.0
    # The car's 0.4 m square padded by the default 0.01 m: inscribed 0.2 + 0.01 / sqrt(2) along the diagonal.
    assert cfg.inscribed_radius == pytest.approx(0.2 + 0.01 / math.sqrt(2), abs=1e-6)
    assert cfg.circumscribed_radius == pytest.approx(0.2 * math.sqrt(2) + 0.01, abs=1e-6)


def test_mbot_common_params_give_a_round_footprint():
    cfg = CostmapConfig('global_costmap', tutorial_costmap('global_costmap', 'mbot/costmap_common_params.yaml'),
                        lambda w: None)
    # A 16-gon touching the 0.2 m circle, its corners pushed out 0.01 m: edges at 0.2 + 0.01 cos(pi / 16).
    assert cfg.inscribed_radius == pytest.approx(0.2 + 0.01 * math.cos(math.pi / 16), abs=1e-6)
    assert cfg.obstacle['sources']['scan'].sensor_frame == 'laser_link'


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
    assert cfg.static['map_topic'] == '/slam_map' and not cfg.static['track_unknown_space']
    assert cfg.obstacle['sources']['front'].obstacle_range == 4.0  # the layer's value is the source default
    assert cfg.inflation['inflation_radius'] == 0.9


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
    p, ros = local_planner_params(load('base_local_planner_params.yaml')['TrajectoryPlannerROS'],
                                  '/move_base/TrajectoryPlannerROS', warnings.append, 10.0)
    assert (p.max_vel_x, p.min_vel_x, p.max_vel_theta, p.min_vel_theta) == (0.3, 0.05, 1.0, -1.0)
    assert p.min_in_place_vel_theta == 0.5  # the new name wins over min_in_place_rotational_vel: 0.01
    assert (p.path_distance_bias, p.goal_distance_bias) == (0.8, 0.4)  # from pdist_scale / gdist_scale
    assert p.meter_scoring and not p.holonomic_robot and not p.dwa
    assert p.sim_period == pytest.approx(1 / 3.0)  # the namespace's controller_frequency wins, as searchParam
    assert (p.sim_time, p.vx_samples, p.vtheta_samples) == (1.7, 20, 20)  # dynamic_reconfigure defaults
    assert ros['xy_goal_tolerance'] == 0.1 and ros['yaw_goal_tolerance'] == 0.1
    text = '\n'.join(warnings)
    assert 'pdist_scale is deprecated' in text and 'max_rotational_vel has no effect' in text


def test_static_layer_values_follow_costmap_2d():
    data = np.array([[-1, 0, 50, 99, 100]], np.int8)
    params = {'unknown_cost_value': -1, 'trinary_costmap': True, 'lethal_cost_threshold': 100,
              'track_unknown_space': True}
    assert static_costs(data, params).tolist() == [[UNKNOWN, FREE, FREE, FREE, LETHAL]]
    params['track_unknown_space'] = False
    assert static_costs(data, params)[0, 0] == FREE


def test_combine_max_ignores_unknown_layer_cells():
    master = np.array([[UNKNOWN, 10, 200, FREE]], np.uint8)
    layer = np.array([[LETHAL, UNKNOWN, 100, INSCRIBED]], np.uint8)
    combine_max(master, layer)
    assert master.tolist() == [[LETHAL, 10, 200, INSCRIBED]]


def test_layered_costmap_marks_clears_and_inflates_and_follows_a_growing_map():
    values = dict(tutorial_costmap('global_costmap'))
    cfg = CostmapConfig('global_costmap', values, lambda w: None)
    lc = LayeredCostmap(cfg, print)
    assert not lc.ready
    lc.set_map(np.zeros((40, 40), np.int8), (0.0, 0.0), 0.05)
    # A scan from (0.5, 1.0) facing +x with one beam hitting at 1.0 m: (1.5, 1.0) is lethal, inflated around.
    assert lc.add_scan('scan', 1.0, (0.5, 1.0, 0.0), 0.2, 0.0, 0.1, 0.1, 6.0, [1.0])
    costs = lc.update((0.5, 1.0, 0.0))
    hit = lc.world_to_cell(1.5, 1.0)
    assert costs[hit[1], hit[0]] == LETHAL
    near = lc.world_to_cell(1.35, 1.0)
    assert costs[near[1], near[0]] == INSCRIBED
    # SLAM grows the map to the left: the mark keeps its world position.
    lc.set_map(np.zeros((40, 60), np.int8), (-1.0, 0.0), 0.05)
    costs = lc.update((0.5, 1.0, 0.0))
    hit = lc.world_to_cell(1.5, 1.0)
    assert costs.shape == (40, 60) and costs[hit[1], hit[0]] == LETHAL
    # The obstacle moved away: the beam now returns nothing (+inf) and clears the cell.
    lc.add_scan('scan', 2.0, (0.5, 1.0, 0.0), 0.2, 0.0, 0.1, 0.1, 6.0, [float('inf')])
    costs = lc.update((0.5, 1.0, 0.0))
    assert costs[hit[1], hit[0]] == FREE


def test_a_sensor_above_max_obstacle_height_is_reported_once():
    warnings = []
    lc = LayeredCostmap(CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), lambda w: None), warnings.append)
    for _ in range(3):
        assert not lc.add_scan('scan', 1.0, (0, 0, 0), 0.5, 0.0, 0.1, 0.1, 6.0, [1.0])
    assert len(warnings) == 1 and 'max_obstacle_height 0.400' in warnings[0]


def test_rolling_window_follows_the_robot():
    lc = LayeredCostmap(CostmapConfig('local_costmap', tutorial_costmap('local_costmap'), lambda w: None), print)
    lc.update((10.0, -3.0, 0.0))
    assert lc.shape == (100, 100)
    assert lc.origin[0] == pytest.approx(7.5) and lc.origin[1] == pytest.approx(-5.5)


def test_prune_plan_drops_what_the_robot_passed():
    plan = np.array([[x, 0.0] for x in np.arange(0, 5, 0.5)])
    assert prune_plan(plan, (2.4, 0.0))[0][0] == pytest.approx(1.5)


def test_param_reader_types():
    r = ParamReader({'a': True, 'b': '1'}, '/ns', lambda w: None)
    with pytest.raises(ParamError, match='/ns/a must be a number'):
        r.number('a', 0.0)
    with pytest.raises(ParamError, match='/ns/b must be true or false'):
        r.boolean('b', False)
