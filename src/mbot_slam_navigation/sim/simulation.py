"""The simulation without ROS: a 2D world, robots with drives and lasers, and simulated time.

All poses are (x [m], y [m], yaw [rad]) of base frames in the world frame; time is seconds of
simulated time. The hot loops (ray casting, collision) run in the C++ core.
"""
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.sim.sdf_world import World
from mbot_slam_navigation.transforms import compose2d
from mbot_slam_navigation.sim.urdf_robot import LaserSpec, RobotSpec

Pose2D = Tuple[float, float, float]


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
        self.geometry = _core._World2D(0.5)
        for s in world.shapes:
            if s.kind == 'box':
                self.geometry.add_box(np.array([s.x, s.y]), s.yaw, s.size_x, s.size_y)
            else:
                self.geometry.add_cylinder(np.array([s.x, s.y]), s.radius)

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return round(self.steps * self.step_size, 9)

    # --- models -------------------------------------------------------------------------------
    def spawn(self, name: str, spec: RobotSpec, pose: Pose2D, namespace: str = '') -> Robot:
        if name in self.robots:
            raise SimulationError('a model named "%s" exists already' % name)
        params = _core._DiffDriveParams()
        params.wheel_separation = spec.drive.wheel_separation
        params.wheel_diameter = spec.drive.wheel_diameter
        params.wheel_acceleration = spec.drive.wheel_acceleration
        params.cmd_timeout = self.cmd_timeout
        params.slip_stddev = self.slip_stddev
        params.odometry_from_world = spec.drive.odometry_source == 'world'
        seed = self.seed * 7919 + len(self.robots) + 1
        drive = _core._DiffDrive(params, [np.asarray(v, float) for v in spec.footprint], np.asarray(pose, float), seed)
        robot = Robot(name=name, namespace=namespace, spec=spec, drive=drive, spawn_pose=tuple(pose),
                      lasers=[Laser(l, _core._Rng(seed * 31 + i), self.time) for i, l in enumerate(spec.lasers)],
                      next_odom_time=self.time)
        self._update_dynamic(extra=robot)
        if self.geometry.overlaps(drive.footprint_in_world(), len(self.robots)):
            raise SimulationError('model "%s" at (%.2f, %.2f) would overlap an obstacle' % (name, pose[0], pose[1]))
        self.robots[name] = robot
        return robot

    def delete(self, name: str) -> None:
        self.get(name)
        del self.robots[name]
        self._update_dynamic()

    def get(self, name: str) -> Robot:
        try:
            return self.robots[name]
        except KeyError:
            raise SimulationError('no model named "%s" (models: %s)'
                                  % (name, ', '.join(self.robots) or 'none')) from None

    def set_pose(self, name: str, pose: Pose2D) -> None:
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
        self.steps = 0
        self._update_dynamic()

    def command(self, name: str, v: float, w: float) -> bool:
        """Velocity command; False (and ignored) when v or w is not finite."""
        return self.get(name).drive.command(float(v), float(w), self.time)

    # --- stepping -----------------------------------------------------------------------------
    def step(self) -> List[Robot]:
        """Advances one step; returns the robots that came into contact with something."""
        new_contacts = []
        for i, r in enumerate(self.robots.values()):
            blocked = r.drive.step(self.step_size, self.time, self.geometry, i)
            if blocked and not r.in_contact:
                r.collisions += 1
                new_contacts.append(r)
            r.in_contact = blocked
        self.steps += 1
        if len(self.robots) > 1:
            self._update_dynamic()
        return new_contacts

    def scan(self, robot: Robot, laser: Laser) -> np.ndarray:
        """A scan from the laser's current pose: float32 ranges, REP 117."""
        s = laser.spec
        index = list(self.robots).index(robot.name)
        return _core._cast_scan(self.geometry, np.asarray(robot.laser_pose(laser), float), s.angle_min,
                                s.angle_increment, s.samples, s.range_min, s.range_max, s.noise_stddev,
                                s.range_resolution, laser.rng, index)

    def _update_dynamic(self, extra: Optional[Robot] = None) -> None:
        robots = list(self.robots.values()) + ([extra] if extra is not None else [])
        self.geometry.set_dynamic_polygons([r.drive.footprint_in_world() for r in robots])
