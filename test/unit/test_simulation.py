"""The ROS-free simulation: a robot in the home world drives, sees walls and collides."""
import math
import os

import pytest

from mbot_slam_navigation.sim.sdf_world import load_world
from mbot_slam_navigation.sim.simulation import Simulation, SimulationError
from mbot_slam_navigation.sim.urdf_robot import LaserSpec, parse_urdf
from test_urdf_robot import BASE, DRIVE, PKG

HOME = os.path.join(PKG, 'worlds', 'mbot_sim_gazebo_navigation.world')


def robot_spec():
    spec = parse_urdf(BASE % DRIVE)
    spec.lasers = [LaserSpec(name='l', link='laser', samples=360, angle_min=-math.pi,
                             angle_max=math.pi - 2 * math.pi / 360, range_max=10.0)]
    return spec


def run(sim, name, v, w, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.command(name, v, w)
        sim.step()


def test_scan_sees_the_known_walls():
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    robot = sim.spawn('r', robot_spec(), (-2.0, -1.0, 0.0))
    ranges = sim.scan(robot, robot.lasers[0])
    # From (-2, -1): the y = 0.9 wall's south face is 1.85 m north (beam at +90 deg is index 270),
    # the west wall's inner face (x = -5.35) 3.35 m west (index 0).
    assert ranges[270] == pytest.approx(1.85, abs=1e-6)
    assert ranges[0] == pytest.approx(3.35, abs=1e-6)


def test_collision_stops_and_counts_once():
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    sim.spawn('r', robot_spec(), (-2.0, -1.0, math.pi / 2))
    run(sim, 'r', 0.5, 0.0, 8.0)
    r = sim.get('r')
    assert r.collisions == 1
    assert r.pose[1] + 0.3 <= 0.85 + 1e-6   # body's front (0.3 m ahead) never passes the wall face
    assert r.pose[1] + 0.3 > 0.84


def test_errors_name_the_model():
    sim = Simulation(load_world(HOME))
    sim.spawn('r', robot_spec(), (0.0, 0.0, 0.0))
    with pytest.raises(SimulationError, match='exists already'):
        sim.spawn('r', robot_spec(), (-1.0, -1.0, 0.0))
    with pytest.raises(SimulationError, match='would overlap'):
        sim.spawn('in_wall', robot_spec(), (1.2, -4.5, 0.0))
    with pytest.raises(SimulationError, match=r'no model named "ghost" \(models: r\)'):
        sim.command('ghost', 1.0, 0.0)
    assert sim.command('r', float('nan'), 0.0) is False


def test_two_robots_see_and_block_each_other():
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    a = sim.spawn('a', robot_spec(), (-3.0, -2.0, 0.0))
    sim.spawn('b', robot_spec(), (-1.5, -2.0, math.pi))
    assert sim.scan(a, a.lasers[0])[180] == pytest.approx(1.5 - 0.3, abs=1e-6)  # b's rear face
    run(sim, 'a', 0.4, 0.0, 5.0)
    assert a.collisions == 1 and sim.get('b').pose[0] == pytest.approx(-1.5)
