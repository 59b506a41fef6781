"""SDF world reading: nested poses, the state block, cylinders, and what is reported."""
import math
import os

import pytest

from mbot_slam_navigation.sim.sdf_world import load_world, parse_world
from mbot_slam_navigation.sim.xmlutil import XmlError

DATA = os.path.join(os.path.dirname(__file__), '..', 'data')
PKG = os.path.join(os.path.dirname(__file__), '..', '..')


def shape(world, name):
    return next(s for s in world.shapes if s.name.startswith(name + '/'))


def test_poses_compose_model_link_collision():
    w = load_world(os.path.join(DATA, 'nested_poses.world'))
    s = shape(w, 'rotated')
    # model (1, 2, +90 deg) o link (1, 0) o collision (0, 1, yaw 0.5): link at (1, 3), collision at (0, 3)
    assert s.kind == 'box'
    assert s.x == pytest.approx(0.0, abs=1e-9) and s.y == pytest.approx(3.0, abs=1e-9)
    assert s.size_x == pytest.approx(0.4) and s.size_y == pytest.approx(0.2)
    # roll and pitch of the collision are dropped only after composing; yaw stays close to 90 + 28.6 deg
    assert abs(s.yaw - (math.pi / 2 + 0.5)) < 0.05


def test_state_block_overrides_the_model_pose():
    s = shape(load_world(os.path.join(DATA, 'nested_poses.world')), 'moved')
    assert (s.x, s.y, s.yaw) == pytest.approx((-3.0, -4.0, 0.25))


def test_cylinder_becomes_a_circle():
    s = shape(load_world(os.path.join(DATA, 'nested_poses.world')), 'plant')
    assert s.kind == 'circle' and s.radius == pytest.approx(0.25) and (s.x, s.y) == pytest.approx((5, 5))


def test_unusable_elements_are_reported_with_their_line():
    w = load_world(os.path.join(DATA, 'nested_poses.world'))
    text = '\n'.join(w.warnings)
    assert 'nested_poses.world:6: <include>' in text and 'model://bookshelf' in text
    assert 'nested_poses.world:22: <model name="statue">: 1 <mesh> collision left out' in text
    assert 'ground_plane' not in text and 'sun' not in text  # skipped quietly, as Gazebo users expect
    assert len(w.shapes) == 3


def test_malformed_file_names_the_line():
    with pytest.raises(XmlError, match=r'malformed.world:6: malformed XML: mismatched tag'):
        load_world(os.path.join(DATA, 'malformed.world'))


def test_missing_file_and_bad_values():
    with pytest.raises(XmlError, match='does not exist'):
        load_world('/nonexistent/home.world')
    bad = ('<sdf><world name="w"><model name="m"><link name="l"><collision name="c"><geometry>'
           '<box><size>1 0</size></box></geometry></collision></link></model></world></sdf>')
    with pytest.raises(XmlError, match=r'<collision name="c"> <box><size>: expected 3 numbers'):
        parse_world(bad, 'bad.world')


def test_shipped_worlds_load_without_warnings():
    home = load_world(os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world'))
    assert home.warnings == [] and len(home.shapes) >= 30
    wall = load_world(os.path.join(PKG, 'worlds', 'wall.world'))
    assert wall.warnings == []


def test_bounds_of_the_home():
    xmin, ymin, xmax, ymax = load_world(os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world')).bounds()
    # Outer wall faces: balcony west wall x = -7.5 - 0.05, east x = 4.5 + 0.05, south y = -6.05, north 3.65.
    assert (xmin, ymin, xmax, ymax) == pytest.approx((-7.6, -6.1, 4.6, 3.7), abs=0.06)
