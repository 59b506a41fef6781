"""The exploration tutorial's pieces without a running ROS: random_navigation's table, locations
files, rounds and log lines, and what its two launch files put on the parameter server."""
import functools
import math
import os
import random

import numpy as np
import pytest

from mbot_slam_navigation.launch_files import launch_config, node_params
from mbot_slam_navigation.nav.random_navigation import (GOAL_STATES, TUTORIAL_LOCATIONS, LocationsError, Tally,
                                                        load_locations, next_round, trunc, tutorial_locations)
from mbot_slam_navigation.sim.ground_truth import distance_to_surfaces, rasterize
from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.transforms import quaternion_to_yaw

ROOT = os.path.join(os.path.dirname(__file__), '..', '..')
LAUNCH = os.path.join(ROOT, 'launch')


@functools.lru_cache(maxsize=None)
def world_grid(name):
    world = load_world(os.path.join(ROOT, 'worlds', name))
    return (world,) + rasterize(world, 0.05)


def in_free_space(world_name, x, y, clearance):
    """True when (x, y) [m] is outside every shape of the world and `clearance` [m] from all of them."""
    world, grid, origin = world_grid(world_name)
    row, col = int((y - origin[1]) / 0.05), int((x - origin[0]) / 0.05)
    return grid[row, col] == 0 and distance_to_surfaces(world, np.array([[x, y]]))[0] > clearance


def test_the_tutorial_points_are_unit_quaternions_with_the_same_heading_and_reachable():
    locations = tutorial_locations()
    assert [loc.name for loc in locations] == ['p%d' % i for i in range(1, 10)]
    assert [loc.room for loc in locations][:3] == ['kitchen', 'dining room', 'bathroom']
    for loc, (_, _, x, y, q) in zip(locations, TUTORIAL_LOCATIONS):
        assert math.isclose(np.linalg.norm(loc.orientation), 1.0, abs_tol=1e-9)
        assert loc.note and 'normalized' in loc.note  # every point of the tutorial needs it
        yaw = quaternion_to_yaw(*np.array(q) / np.linalg.norm(q))
        assert math.isclose(math.cos(quaternion_to_yaw(*loc.orientation) - yaw), 1.0, abs_tol=1e-9)
        assert in_free_space('mbot_sim_gazebo_navigation.world', x, y, 0.25), loc.name  # room for the mbot (radius 0.2 m)


def test_rounds_visit_every_point_and_never_repeat_the_last():
    rng = random.Random(3)
    names = ['p%d' % i for i in range(1, 10)]
    last = ''
    for _ in range(200):
        order = next_round(rng, names, last)
        assert sorted(order) == sorted(names)
        assert order[0] != last
        last = order[-1]
    assert next_round(random.Random(1), ['only'], 'only') == ['only']


def test_the_same_seed_gives_the_same_rounds():
    names = ['p%d' % i for i in range(1, 10)]
    assert next_round(random.Random(7), names, 'p1') == next_round(random.Random(7), names, 'p1')


def test_log_lines_as_the_tutorial_prints_them():
    t = Tally()
    t.record('p1', 'SUCCEEDED', 2.36)
    t.record('p2', 'ABORTED', 5.0)
    t.record('p3', 'SUCCEEDED', 1.0)
    assert t.success_line() == 'Success so far: 2/3 = 66%'
    assert t.time_line(125.0) == 'Running time: 2.0 min Distance: 3.3 m'
    summary = t.summary(125.0, tutorial_locations())
    assert summary.splitlines()[0] == 'Random navigation summary: 3 goals, 2 succeeded (66.7%), 2.1 min, 3.4 m'
    assert 'p2 (dining room)' in summary and 'failed: ABORTED' in summary
    assert GOAL_STATES[3] == 'SUCCEEDED' and GOAL_STATES[4] == 'ABORTED' and len(GOAL_STATES) == 10


@pytest.mark.parametrize('value, n, expected', [(2.39, 1, 2.3), (1e-05, 1, 0.0), (-1.27, 1, -1.2), (17.0, 1, 17.0),
                                                (123456789.987, 2, 123456789.98)])
def test_trunc_cuts_towards_zero_even_in_exponent_form(value, n, expected):
    assert trunc(value, n) == pytest.approx(expected)


def test_locations_file_in_both_forms(tmp_path):
    f = tmp_path / 'points.yaml'
    f.write_text('a: {room: hall, position: [1.0, 2.0], yaw: 1.5707963}\n'
                 'b: {position: [3, 4, 0], orientation: [0, 0, 0, 2]}\n')
    a, b = load_locations(str(f))
    assert (a.name, a.room, a.x, a.y) == ('a', 'hall', 1.0, 2.0)
    assert quaternion_to_yaw(*a.orientation) == pytest.approx(math.pi / 2) and a.note == ''
    assert b.orientation == pytest.approx((0, 0, 0, 1)) and 'normalized' in b.note


def test_wall_locations_example_lies_in_free_space_of_wall_world():
    locations = load_locations(os.path.join(ROOT, 'config', 'wall_locations.yaml'))
    assert len(locations) >= 3
    for loc in locations:
        assert in_free_space('wall.world', loc.x, loc.y, 0.5), loc.name


@pytest.mark.parametrize('text, key, words', [
    ('a: {position: [1, 2]}\n', 'a', 'exactly one of orientation'),
    ('a: {position: [1], yaw: 0}\n', 'a.position', '[x, y]'),
    ('a: {position: [1, .nan], yaw: 0}\n', 'a.position', '[x, y]'),
    ('a: {position: [1, 2], orientation: [0, 0, 0]}\n', 'a.orientation', 'quaternion'),
    ('a: {position: [1, 2], orientation: [0, 0, 0, 0]}\n', 'a.orientation', 'zero quaternion'),
    ('a: {position: [1, 2], orientation: [0.7, 0, 0, 0.7]}\n', 'a.orientation', 'tilts'),
    ('a: {position: [1, 2], yaw: east}\n', 'a.yaw', 'radians'),
    ('a: {positon: [1, 2], yaw: 0}\n', 'a.positon', 'unknown key'),
    ('a: {yaw: 0}\n', 'a.position', 'missing'),
    ('a: [1, 2]\n', 'a', 'mapping'),
    ('- a\n', '', 'must map point names'),
    ('a: {position: [1, 2], yaw: 0\n', '', 'not valid YAML'),
])
def test_bad_locations_files_name_the_file_and_key(tmp_path, text, key, words):
    f = tmp_path / 'bad.yaml'
    f.write_text(text)
    with pytest.raises(LocationsError) as e:
        load_locations(str(f))
    assert e.value.key == key and str(f) in str(e.value) and words in str(e.value)


def test_missing_locations_file():
    with pytest.raises(LocationsError, match='cannot read the file'):
        load_locations('/nonexistent/points.yaml')


def test_navigation_launch_is_the_tutorials_with_slam_owning_map_to_odom():
    config = launch_config(os.path.join(LAUNCH, 'robot_gazebo_navigation.launch'), ['gui:=false', 'rviz:=false'])
    nodes = {n.name: n for n in config.nodes}
    assert set(nodes) == {'gazebo', 'urdf_spawner', 'joint_state_publisher', 'robot_state_publisher', 'slam_gmapping'}
    assert config.params['/slam_gmapping/base_frame'].value == 'base_footprint'
    assert config.params['/gazebo/world_name'].value.endswith('worlds/mbot_sim_gazebo_navigation.world')
    assert config.params['/use_sim_time'].value is True
    assert 'name="mbot"' in config.params['/robot_description'].value
    assert ('robot/laser/scan', '/scan') in [tuple(r) for r in nodes['gazebo'].remap_args]
    assert nodes['urdf_spawner'].args == '-urdf -model robot -param robot_description -z 0.05'
    with_rviz = launch_config(os.path.join(LAUNCH, 'robot_gazebo_navigation.launch'))
    rviz = [n for n in with_rviz.nodes if n.name == 'rviz'][0]
    assert rviz.args.endswith('urdf/xacro/default.rviz') and os.path.isfile(rviz.args.split()[-1])


def test_move_launch_has_the_tutorials_move_base_and_no_competing_amcl():
    path = os.path.join(LAUNCH, 'robot_gazebo_navigation_move.launch')
    assert [n.name for n in launch_config(path).nodes] == ['move_base']
    mb = node_params(path, '/move_base')
    assert (mb['controller_frequency'], mb['controller_patiente']) == (10.0, 15.0)
    assert mb['local_costmap/robot_radius'] == 0.2 and mb['local_costmap/scan/sensor_frame'] == 'laser_link'
    assert mb['TrajectoryPlannerROS/max_vel_x'] == 0.3 and mb['global_costmap/static_map'] is True
    amcl = node_params(path, '/amcl', ['amcl:=true'])
    assert amcl['tf_broadcast'] is False and amcl['use_map_topic'] is True and amcl['min_particles'] == 500


def test_the_patrol_example_is_the_tutorials_table_and_the_order_is_checked():
    """config/home_patrol.yaml (launch/patrol.launch's points) holds the tutorial's nine points, in order."""
    from mbot_slam_navigation.nav.params import ParamError, ParamReader
    from mbot_slam_navigation.nav.random_navigation import read_parameters
    here = os.path.dirname(os.path.abspath(__file__))
    patrol = load_locations(os.path.join(here, '..', '..', 'config', 'home_patrol.yaml'))
    table = tutorial_locations()
    assert [p.name for p in patrol] == [t.name for t in table]
    for p, t in zip(patrol, table):
        assert (p.x, p.y, p.room) == (t.x, t.y, t.room)
        assert abs(math.remainder(quaternion_to_yaw(*p.orientation) - quaternion_to_yaw(*t.orientation), 2 * math.pi)) < 1e-3
    launch = node_params(os.path.join(here, '..', '..', 'launch', 'patrol.launch'), '/patrol')
    assert launch['order'] == 'sequence'
    assert read_parameters(ParamReader({'order': 'sequence', 'rounds': 2}, '/patrol', print))['rounds'] == 2
    with pytest.raises(ParamError, match="/patrol/order must be 'random' or 'sequence'"):
        read_parameters(ParamReader({'order': 'shuffled'}, '/patrol', print))
