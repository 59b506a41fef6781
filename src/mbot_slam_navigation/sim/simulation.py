"""The simulation without ROS: a 2D world, robots with drives and lasers, and simulated time.

All poses are (x [m], y [m], yaw [rad]) of base frames in the world frame; time is seconds of
simulated time. The hot loops (ray casting, collision) run in the C++ core.

Heights: a shape stops a robot if it overlaps the robot's body (from GROUND_CLEARANCE to the top
of its URDF collision geometry) and a laser sees it if the laser's scan plane cuts it; a lintel over
a door or a table top above the robot does neither.

People (SDF actors) walk their scripts; lasers see them and robots collide with them. A person
yields: while its next step would bring it within YIELD_MARGIN of a robot (and closer than it is),
its script waits; after PERSON_PATIENCE s of waiting it walks on regardless, as Gazebo's actors
always do, so that nothing waits forever. A contact is the robot's fault only when the robot moved
into what it touched; a person walking into a robot is counted, but as the person's, and so is a
person who, in the step the two met, walked at the robot farther than the robot moved (which of
them closed the last millimetre is then chance, not fault).
"""
import math
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.sim.sdf_world import Actor, World
from mbot_slam_navigation.transforms import compose2d
from mbot_slam_navigation.sim.urdf_robot import LaserSpec, RobotSpec

Pose2D = Tuple[float, float, float]
YIELD_MARGIN = 0.1      # [m] a person keeps this gap to a robot while it can
PERSON_PATIENCE = 10.0  # [s] of simulated time a person waits for a robot before walking on
TOUCH = 0.02            # [m] a robot stopped this close to a person touched it
GROUND_CLEARANCE = 0.01  # [m] shapes lower than this (floor tiles, mats) are driven over
SPAWN_SEARCH = 5.0      # [m] how far from a spawn pose in a wall the nearest free place is looked for


@dataclass
class Person:
    actor: Actor
    script_time: float = 0.0          # [s] of its script played (stops while it yields)
    waited: float = 0.0               # [s] yielding so far, without a step
    closing: float = 0.0              # [m] how much nearer to a robot its last step took it (0: none)
    pose: Pose2D = (0.0, 0.0, 0.0)
    added_at: float = 0.0             # [s] simulated time it came in (0 for the world's, and after a reset)

    @property
    def name(self) -> str:
        return self.actor.name


@dataclass
class ContactEvent:
    """A robot came into contact with something: 'world' (walls, furniture), a person or a robot."""
    robot: 'Robot'
    other: str                        # 'world', or the person's or robot's model name
    kind: str                         # 'world', 'person' or 'robot'
    robot_at_fault: bool              # the robot moved into it


@dataclass
class Laser:
    spec: LaserSpec
    rng: object
    next_time: float = 0.0


@dataclass
class Robot:
    name: str
    namespace: str
    spec: RobotSpec
    drive: object                      # _core._DiffDrive
    spawn_pose: Pose2D
    lasers: List[Laser] = field(default_factory=list)
    collisions: int = 0                # contact episodes so far
    in_contact: bool = False
    at_fault_collisions: int = 0       # episodes where the robot moved into what it touched
    next_odom_time: float = 0.0

    @property
    def pose(self) -> Pose2D:
        p = self.drive.pose
        return float(p[0]), float(p[1]), float(p[2])

    def laser_pose(self, laser: Laser) -> Pose2D:
        return compose2d(self.pose, laser.spec.pose_in_base)


class SimulationError(ValueError):
    """A request the simulation cannot serve (unknown robot, spawn in a wall, ...)."""


class Simulation:
    def __init__(self, world: World, step_size: float = 0.01, slip_stddev: float = 0.02,
                 cmd_timeout: float = 0.5, seed: int = 0):
        if not step_size > 0:
            raise SimulationError('step_size must be positive, got %r' % step_size)
        self.world = world
        self.step_size = step_size
        self.slip_stddev = slip_stddev
        self.cmd_timeout = cmd_timeout
        self.seed = seed
        self.steps = 0  # time is counted in whole steps so that stamps do not drift by rounding
        self.robots: Dict[str, Robot] = OrderedDict()
        self.people: Dict[str, Person] = OrderedDict()
        self.geometry = _core._World2D(0.5)
        for s in world.shapes:
            if s.kind == 'box':
                self.geometry.add_box(np.array([s.x, s.y]), s.yaw, s.size_x, s.size_y, s.z_lo, s.z_hi)
            elif s.kind == 'circle':
                self.geometry.add_cylinder(np.array([s.x, s.y]), s.radius, s.z_lo, s.z_hi)
            else:
                self.geometry.add_grid(s.cells.astype(np.uint8), np.array([s.x, s.y]), s.yaw, s.resolution,
                                       s.z_lo, s.z_hi)
        for actor in world.actors:
            self.add_person(actor)

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return round(self.steps * self.step_size, 9)

    # --- models -------------------------------------------------------------------------------
    def add_person(self, actor: Actor) -> Person:
        """A person (an SDF actor) that walks its script from the current time on."""
        if actor.name in self.robots or actor.name in self.people:
            raise SimulationError('a model named "%s" exists already' % actor.name)
        if not actor.radius > 0:
            raise SimulationError('person "%s": radius must be positive, got %r' % (actor.name, actor.radius))
        person = Person(actor, pose=actor.pose_at(0.0), added_at=self.time)
        self.people[actor.name] = person
        self._update_people()
        return person

    def spawn(self, name: str, spec: RobotSpec, pose: Pose2D, namespace: str = '') -> Robot:
        if name in self.robots or name in self.people:
            raise SimulationError('a model named "%s" exists already' % name)
        params = _core._DiffDriveParams()
        params.wheel_separation = spec.drive.wheel_separation
        params.wheel_diameter = spec.drive.wheel_diameter
        params.wheel_acceleration = spec.drive.wheel_acceleration
        params.cmd_timeout = self.cmd_timeout
        params.slip_stddev = self.slip_stddev
        params.odometry_from_world = spec.drive.odometry_source == 'world'
        params.set_body_heights(GROUND_CLEARANCE, spec.height)
        seed = self.seed * 7919 + len(self.robots) + 1
        drive = _core._DiffDrive(params, [np.asarray(v, float) for v in spec.footprint], np.asarray(pose, float), seed)
        robot = Robot(name=name, namespace=namespace, spec=spec, drive=drive, spawn_pose=tuple(pose),
                      lasers=[Laser(l, _core._Rng(seed * 31 + i), self.time) for i, l in enumerate(spec.lasers)],
                      next_odom_time=self.time)
        self._update_dynamic(extra=robot)
        if self.geometry.overlaps(drive.footprint_in_world(), len(self.robots), GROUND_CLEARANCE, spec.height):
            free = self.nearest_free(spec, pose, len(self.robots))
            raise SimulationError('model "%s" at (%.2f, %.2f) would overlap an obstacle; %s'
                                  % (name, pose[0], pose[1], 'the nearest free place is (%.2f, %.2f)' % free
                                     if free else 'no free place within %.0f m' % SPAWN_SEARCH))
        self.robots[name] = robot
        return robot

    def nearest_free(self, spec: RobotSpec, pose: Pose2D, skip: int = -1, step: float = 0.05) -> Optional[Tuple[float, float]]:
        """(x, y) [m] nearest to `pose` (same yaw, on rings `step` apart) where the robot fits, or None
        within SPAWN_SEARCH."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        foot = np.asarray(spec.footprint, float) @ np.array([[c, s], [-s, c]])
        for k in range(1, int(SPAWN_SEARCH / step) + 1):
            r = k * step
            n = max(8, int(2 * math.pi * r / step))
            for a in np.arange(n) * 2 * math.pi / n:
                x, y = pose[0] + r * math.cos(a), pose[1] + r * math.sin(a)
                if not self.geometry.overlaps(foot + (x, y), skip, GROUND_CLEARANCE, spec.height):
                    return x, y
        return None

    def delete(self, name: str) -> None:
        if name in self.people:
            del self.people[name]
            self._update_people()
            return
        self.get(name)
        del self.robots[name]
        self._update_dynamic()

    def model_pose(self, name: str) -> Pose2D:
        """The pose of a robot or a person."""
        if name in self.people:
            return self.people[name].pose
        return self.get(name).pose

    def get(self, name: str) -> Robot:
        try:
            return self.robots[name]
        except KeyError:
            if name in self.people:
                raise SimulationError('"%s" is a person, not a robot' % name) from None
            raise SimulationError('no model named "%s" (models: %s)'
                                  % (name, ', '.join(list(self.robots) + list(self.people)) or 'none')) from None

    def set_pose(self, name: str, pose: Pose2D) -> None:
        person = self.people.get(name)
        if person is not None:
            if person.actor.waypoints and person.actor.auto_start:
                raise SimulationError('person "%s" follows its script; delete it and spawn one without a script '
                                      'to place it' % name)
            person.actor.x, person.actor.y, person.actor.yaw = pose
            person.pose = tuple(pose)
            self._update_people()
            return
        self.get(name).drive.set_pose(np.asarray(pose, float))
        self._update_dynamic()

    def reset(self) -> None:
        """Gazebo's reset_simulation: robots back to their spawn poses, odometry and time to zero."""
        for r in self.robots.values():
            r.drive.set_pose(np.asarray(r.spawn_pose, float))
            r.drive.reset_odometry()
            r.drive.command(0.0, 0.0, 0.0)
            r.next_odom_time = 0.0
            for l in r.lasers:
                l.next_time = 0.0
        for p in self.people.values():
            p.script_time, p.waited, p.pose, p.added_at = 0.0, 0.0, p.actor.pose_at(0.0), 0.0
        self.steps = 0
        self._update_dynamic()
        self._update_people()

    def command(self, name: str, v: float, w: float) -> bool:
        """Velocity command; False (and ignored) when v or w is not finite."""
        return self.get(name).drive.command(float(v), float(w), self.time)

    # --- stepping -----------------------------------------------------------------------------
    def step(self) -> List[ContactEvent]:
        """Advances one step; returns the contacts that began in it."""
        new_contacts = []
        walked_into = self._step_people() if self.people else {}
        several = len(self.robots) > 1
        for i, r in enumerate(self.robots.values()):
            v, w = r.drive.linear_velocity, r.drive.angular_velocity
            blocked = r.drive.step(self.step_size, self.time, self.geometry, i)
            if several:
                # The next robot checks its move against this one where it is now: two robots
                # closing on each other in one step would otherwise both move into the same gap,
                # overlap, and never part again (every move from an overlap overlaps).
                self._update_dynamic()
            touching = blocked or r.name in walked_into
            if touching and not r.in_contact:
                if r.name in walked_into:
                    event = ContactEvent(r, walked_into[r.name], 'person', robot_at_fault=False)
                else:
                    other, kind = self._touched_by(r, i)
                    # A person who walked at the robot faster than it moved, in the very step the two
                    # met, walked into it: which of them closed the last millimetre is chance.
                    walked = kind == 'person' and self.people[other].closing > self._reach(r, v, w)
                    event = ContactEvent(r, other, kind, robot_at_fault=not walked)
                r.collisions += 1
                r.at_fault_collisions += event.robot_at_fault
                new_contacts.append(event)
            r.in_contact = touching
        self.steps += 1
        if len(self.robots) > 1 or self.people:
            self._update_dynamic()
        return new_contacts

    def _step_people(self) -> Dict[str, str]:
        """Moves the people one step; returns {robot: person} for people now overlapping a robot."""
        dt, now = self.step_size, self.time
        walked_into = {}
        for p in self.people.values():
            a = p.actor
            p.closing = 0.0
            if now < p.added_at + a.delay_start or not a.waypoints:
                continue
            nx, ny, nyaw = a.pose_at(p.script_time + dt)
            ahead = self.geometry.distance_to_dynamic_polygons(np.array([nx, ny]))
            if ahead < a.radius + YIELD_MARGIN and p.waited < PERSON_PATIENCE:
                here = self.geometry.distance_to_dynamic_polygons(np.array(p.pose[:2]))
                if ahead < here and (nx, ny) != p.pose[:2]:
                    p.waited += dt  # a robot is in the way: wait for it to pass
                    continue
            if ahead >= a.radius + YIELD_MARGIN:
                p.waited = 0.0  # clear of robots; after a wait, it keeps walking until it is
            p.closing = max(0.0, self.geometry.distance_to_dynamic_polygons(np.array(p.pose[:2])) - ahead) \
                if ahead < a.radius + YIELD_MARGIN else 0.0
            p.script_time += dt
            p.pose = (nx, ny, nyaw)
            if ahead < a.radius:
                for r in self.robots.values():
                    if _core._point_polygon_distance(np.array([nx, ny]), r.drive.footprint_in_world()) < a.radius:
                        walked_into[r.name] = p.name
        self._update_people()
        return walked_into

    def _reach(self, robot: Robot, v: float, w: float) -> float:
        """[m] The most one step at (v, w) takes any point of the robot's footprint nearer to something."""
        x, y, _ = robot.pose
        radius = max(math.hypot(px - x, py - y) for px, py in robot.drive.footprint_in_world())
        return (abs(v) + abs(w) * radius) * self.step_size

    def _touched_by(self, robot: Robot, index: int) -> Tuple[str, str]:
        """What a robot that was just stopped touches: ('person name', 'person'), ('robot name',
        'robot') or ('world', 'world')."""
        footprint = robot.drive.footprint_in_world()
        for p in self.people.values():
            if _core._point_polygon_distance(np.array(p.pose[:2]), footprint) < p.actor.radius + TOUCH:
                return p.name, 'person'
        for j, other in enumerate(self.robots.values()):
            if j != index and min(_core._point_polygon_distance(np.asarray(v, float), other.drive.footprint_in_world())
                                  for v in footprint) < TOUCH:
                return other.name, 'robot'
        return 'world', 'world'

    def scan(self, robot: Robot, laser: Laser) -> np.ndarray:
        """A scan from the laser's current pose: float32 ranges, REP 117."""
        s = laser.spec
        index = list(self.robots).index(robot.name)
        return _core._cast_scan(self.geometry, np.asarray(robot.laser_pose(laser), float), s.angle_min,
                                s.angle_increment, s.samples, s.range_min, s.range_max, s.noise_stddev,
                                s.range_resolution, laser.rng, index, s.height)

    def _update_people(self) -> None:
        self.geometry.set_dynamic_circles([np.array([p.pose[0], p.pose[1], p.actor.radius]) for p in self.people.values()])

    def _update_dynamic(self, extra: Optional[Robot] = None) -> None:
        robots = list(self.robots.values()) + ([extra] if extra is not None else [])
        self.geometry.set_dynamic_polygons([r.drive.footprint_in_world() for r in robots])
