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


def test_two_robots_driving_at_each_other_stop_apart_and_can_back_away():
    # Head-on at 0.5 m/s each: a step closes 1 cm, so both would move into the same gap if each
    # checked its move against where the other stood before the step (the gap, 0.297 m, is not a
    # whole number of steps).
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    a = sim.spawn('a', robot_spec(), (-3.0, -2.0, 0.0))
    b = sim.spawn('b', robot_spec(), (-2.103, -2.0, math.pi))
    for _ in range(int(round(4.0 / sim.step_size))):
        sim.command('a', 0.5, 0.0)
        sim.command('b', 0.5, 0.0)
        sim.step()
    assert a.collisions >= 1 and b.collisions >= 1
    gap = b.pose[0] - a.pose[0]
    assert gap >= 0.6 - 1e-6, 'the bodies (0.3 m ahead of each centre) overlap by %.3f m' % (0.6 - gap)
    # both back away
    xa, xb = a.pose[0], b.pose[0]
    for _ in range(int(round(1.0 / sim.step_size))):
        sim.command('a', -0.2, 0.0)
        sim.command('b', -0.2, 0.0)
        sim.step()
    assert a.pose[0] < xa - 0.15 and b.pose[0] > xb + 0.15, (a.pose, b.pose)


PERSON_SDF = '''<sdf version="1.6"><world name="w">
  <actor name="walker"><script><loop>true</loop><delay_start>1.0</delay_start>
    <trajectory id="0" type="walking">
      <waypoint><time>0</time><pose>-4 -2 1 0 0 0</pose></waypoint>
      <waypoint><time>4</time><pose>0 -2 1 0 0 0</pose></waypoint>
    </trajectory>
    <trajectory id="1" type="walking">
      <waypoint><time>0</time><pose>0 -2 1 0 0 3.1416</pose></waypoint>
      <waypoint><time>4</time><pose>-4 -2 1 0 0 3.1416</pose></waypoint>
    </trajectory></script></actor>
</world></sdf>'''


def people_world(text=PERSON_SDF):
    from mbot_slam_navigation.sim.sdf_world import parse_world
    world = load_world(HOME)
    world.actors = parse_world(text).actors
    return world


def test_a_person_walks_the_script_in_order_and_loops():
    sim = Simulation(people_world(), slip_stddev=0.0)
    p = sim.people['walker']
    assert p.pose[:2] == (-4.0, -2.0)
    for t, x in ((0.5, -4.0), (1.0, -4.0), (3.0, -2.0), (5.0, 0.0), (7.0, -2.0), (9.0, -4.0), (11.0, -2.0)):
        while sim.time < t - 1e-9:
            sim.step()
        assert p.pose[0] == pytest.approx(x, abs=0.02), t  # 1 s delay, 4 s out, 4 s back, then again
    assert sim.people['walker'].actor.radius == pytest.approx(0.25)


def test_lasers_see_a_person_and_a_robot_that_drives_into_one_is_at_fault():
    standing = '''<sdf version="1.6"><actor name="bob"><pose>-1 -2 0 0 0 0</pose>
      <link name="l"><collision name="c"><geometry><cylinder><radius>0.3</radius><length>1.7</length></cylinder>
      </geometry></collision></link></actor></sdf>'''
    from mbot_slam_navigation.sim.sdf_world import parse_actors
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    robot = sim.spawn('r', robot_spec(), (-3.0, -2.0, 0.0))
    sim.add_person(parse_actors(standing)[0])
    assert sim.scan(robot, robot.lasers[0])[180] == pytest.approx(2.0 - 0.3, abs=1e-6)  # beam 180 looks along +x
    run(sim, 'r', 0.4, 0.0, 6.0)
    assert robot.collisions == 1 and robot.at_fault_collisions == 1
    assert robot.pose[0] + 0.3 < -1.3 + 1e-6  # stopped at the person's edge
    sim.delete('bob')
    assert sim.scan(robot, robot.lasers[0])[180] > 3.0  # gone: the next thing ahead is far
    with pytest.raises(SimulationError, match='"bob"'):
        sim.delete('bob')


def test_a_person_yields_to_a_robot_then_walks_on_and_it_is_not_the_robots_fault():
    from mbot_slam_navigation.sim import simulation
    sim = Simulation(people_world(), slip_stddev=0.0)
    robot = sim.spawn('r', robot_spec(), (-2.0, -2.0, math.pi / 2))  # standing across the walker's line
    p = sim.people['walker']
    run(sim, 'r', 0.0, 0.0, 4.0)
    # The walker stops short of the robot (its gap kept) and waits ...
    gap = abs(p.pose[0] - (-2.0)) - 0.3 - p.actor.radius   # robot's half width along x is 0.3 at most
    assert p.pose[0] < -2.0 and p.waited > 0.0 and gap > -0.05
    assert robot.collisions == 0
    # ... for PERSON_PATIENCE, then walks on through; counted, but not as the robot's fault.
    furthest = p.pose[0]
    for _ in range(int((simulation.PERSON_PATIENCE + 4.0) / sim.step_size)):
        sim.step()
        furthest = max(furthest, p.pose[0])
    assert furthest > -0.5
    assert robot.collisions == 1 and robot.at_fault_collisions == 0


def test_a_person_walking_into_a_robot_that_backs_slowly_is_not_the_robots_fault(monkeypatch):
    # The walker comes along y = -2 at 1 m/s and, its patience spent, walks on; the robot backs
    # towards it at 0.1 m/s. Which of the two closes the last millimetre is chance (ten times more
    # often the walker); the walker moved ten times faster into the robot, so it walked into it.
    # Twenty starts half a millimetre apart put that last millimetre on either side.
    from mbot_slam_navigation.sim import simulation
    monkeypatch.setattr(simulation, 'PERSON_PATIENCE', 0.0)
    at_fault = contacts = 0
    for k in range(20):
        sim = Simulation(people_world(), slip_stddev=0.0)
        robot = sim.spawn('r', robot_spec(), (-1.0 - 0.0005 * k, -2.0, 0.0))  # facing away from the walker
        for _ in range(int(3.5 / sim.step_size)):
            sim.command('r', -0.1, 0.0)
            sim.step()
            if robot.collisions:
                break
        contacts += robot.collisions
        at_fault += robot.at_fault_collisions
    assert contacts == 20 and at_fault == 0


def test_people_reset_with_the_simulation_and_bad_scripts_name_the_line():
    from mbot_slam_navigation.sim.sdf_world import parse_world
    from mbot_slam_navigation.sim.xmlutil import XmlError
    sim = Simulation(people_world(), slip_stddev=0.0)
    for _ in range(300):
        sim.step()
    assert sim.people['walker'].pose[0] > -4.0
    sim.reset()
    assert sim.people['walker'].pose[:2] == (-4.0, -2.0) and sim.time == 0.0
    bad = PERSON_SDF.replace('<time>4</time><pose>0 -2', '<time>-1</time><pose>0 -2')
    with pytest.raises(XmlError, match=r'people.world:5: <waypoint>.*must not decrease'):
        parse_world(bad, 'people.world')
    with pytest.raises(SimulationError, match='follows its script'):
        sim.set_pose('walker', (0.0, 0.0, 0.0))
    with pytest.raises(SimulationError, match='exists already'):
        sim.add_person(sim.people['walker'].actor)


def test_a_person_added_later_starts_its_script_then_and_again_after_a_reset():
    sim = Simulation(load_world(HOME), slip_stddev=0.0)
    for _ in range(500):
        sim.step()                                    # 5 s in
    sim.add_person(people_world().actors[0])          # delay_start 1 s: walks from 6 s on
    p = sim.people['walker']
    while sim.time < 5.9:
        sim.step()
    assert p.pose[0] == pytest.approx(-4.0)
    while sim.time < 8.0:
        sim.step()
    assert p.pose[0] == pytest.approx(-2.0, abs=0.02)  # 2 s of walking at 1 m/s
    sim.reset()
    while sim.time < 3.0:
        sim.step()
    assert p.pose[0] == pytest.approx(-2.0, abs=0.02)  # after a reset it counts from 0, as the world's do
