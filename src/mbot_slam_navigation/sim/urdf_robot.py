"""Reads what the simulator needs from a URDF: the drive and laser Gazebo plugins, the laser's pose
relative to the robot's base frame, and the 2D footprint (convex hull of all collision geometry).

Plugins understood, with the Gazebo plugins' parameter names and defaults:
- libgazebo_ros_diff_drive.so: commandTopic, odometryTopic, odometryFrame, robotBaseFrame,
  wheelSeparation, wheelDiameter, wheelAcceleration, updateRate, odometrySource, publishOdomTF,
  publishWheelTF, leftJoint, rightJoint;
- libgazebo_ros_skid_steer_drive.so: leftFrontJoint, rightFrontJoint, leftRearJoint, rightRearJoint,
  wheelSeparation, wheelDiameter, commandTopic, odometryTopic, odometryFrame, robotBaseFrame,
  updateRate, broadcastTF, covariance_x, covariance_y, covariance_yaw;
- <sensor type="ray"|"gpu_ray"> with libgazebo_ros_laser.so / libgazebo_ros_gpu_laser.so: samples,
  resolution, min/max_angle, range min/max/resolution, gaussian noise, update_rate, topicName,
  frameName, the sensor's <pose> in its link.
Old tags (torque, wheelTorque, legacyMode, alwaysOn, rosDebugLevel, ...) are accepted and ignored.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from mbot_slam_navigation.transforms import convex_hull, from_xyz_rpy, planar
from mbot_slam_navigation.sim.xmlutil import XmlError, child_text, floats, parse_xml, where

DIFF_DRIVE = 'libgazebo_ros_diff_drive.so'
SKID_STEER = 'libgazebo_ros_skid_steer_drive.so'
LASER_PLUGINS = ('libgazebo_ros_laser.so', 'libgazebo_ros_gpu_laser.so')
IGNORED_DRIVE_TAGS = {'torque', 'wheelTorque', 'legacyMode', 'alwaysOn', 'rosDebugLevel', 'publishTf',
                      'publishWheelJointState', 'robotNamespace', 'odometryRate'}
DRIVE_TAGS = {
    'diff': {'commandTopic', 'odometryTopic', 'odometryFrame', 'robotBaseFrame', 'wheelSeparation',
             'wheelDiameter', 'wheelAcceleration', 'updateRate', 'odometrySource', 'publishOdomTF',
             'publishWheelTF', 'leftJoint', 'rightJoint'},
    'skid': {'leftFrontJoint', 'rightFrontJoint', 'leftRearJoint', 'rightRearJoint', 'wheelSeparation',
             'wheelDiameter', 'commandTopic', 'odometryTopic', 'odometryFrame', 'robotBaseFrame', 'updateRate',
             'broadcastTF', 'covariance_x', 'covariance_y', 'covariance_yaw'},
}


@dataclass
class DriveSpec:
    kind: str                          # 'diff' or 'skid'
    command_topic: str = 'cmd_vel'
    odometry_topic: str = 'odom'
    odometry_frame: str = 'odom'
    robot_base_frame: str = 'base_footprint'
    wheel_separation: float = 0.34     # [m]
    wheel_diameter: float = 0.15       # [m]
    wheel_acceleration: float = 0.0    # [m/s^2] at the rim, 0 = unlimited
    update_rate: float = 100.0         # [Hz] odometry publication
    odometry_source: str = 'world'     # 'world' (exact) or 'encoder' (from wheels, with slip)
    publish_odom_tf: bool = True
    publish_wheel_tf: bool = False
    wheel_joints: List[str] = field(default_factory=list)  # left, right (diff) or lf, rf, lr, rr (skid)
    covariance: List[float] = field(default_factory=lambda: [1e-4, 1e-4, 1e-2])  # x, y, yaw


@dataclass
class LaserSpec:
    name: str
    link: str
    topic: str = 'scan'
    frame_id: str = ''
    pose_in_base: tuple = (0.0, 0.0, 0.0)  # (x [m], y [m], yaw [rad]) in the drive's robot base frame
    z_in_base: float = 0.0                 # [m] the scan plane's height in the robot base frame
    height: float = float('nan')           # [m] the scan plane above the floor (parse_urdf sets it)
    samples: int = 360
    angle_min: float = -math.pi            # [rad]
    angle_max: float = math.pi
    range_min: float = 0.1                 # [m]
    range_max: float = 10.0
    range_resolution: float = 0.0          # [m], 0 = none
    noise_stddev: float = 0.0              # [m]
    update_rate: float = 10.0              # [Hz]

    @property
    def angle_increment(self) -> float:
        return (self.angle_max - self.angle_min) / (self.samples - 1) if self.samples > 1 else 0.0


@dataclass
class WheelJoint:
    """A driven wheel's joint, for publishWheelTF: parent -> child is origin, then a turn about axis."""
    name: str
    parent: str
    child: str
    origin: np.ndarray             # 4x4 joint origin in the parent link
    axis: np.ndarray               # unit rotation axis in the joint frame
    side: int                      # 0 left, 1 right


@dataclass
class RobotSpec:
    name: str
    drive: DriveSpec
    lasers: List[LaserSpec]
    footprint: np.ndarray          # (N, 2) convex polygon [m] in the robot base frame
    warnings: List[str] = field(default_factory=list)
    wheels: List[WheelJoint] = field(default_factory=list)
    height: float = float('inf')   # [m] top of the collision geometry above the floor (its lowest point)


def _bool(text: str) -> bool:
    return text.strip().lower() in ('1', 'true', 'yes')


def parse_urdf(text: str, source: str = 'robot_description') -> RobotSpec:
    """Raises XmlError naming the element when the robot cannot be simulated."""
    root, lines = parse_xml(text, source)
    if root.tag != 'robot':
        raise XmlError('%s: the root element is <%s>, expected <robot>' % (where(source, lines, root), root.tag))
    warnings: List[str] = []
    links = {l.get('name'): l for l in root.findall('link')}
    link_tf = _link_transforms(root, links, source, lines)

    drive = None
    lasers = []
    for gz in root.findall('gazebo'):
        for plugin in gz.findall('plugin'):
            filename = plugin.get('filename', '')
            if filename in (DIFF_DRIVE, SKID_STEER):
                if drive is not None:
                    raise XmlError('%s: a second drive plugin; one robot has one drive' % where(source, lines, plugin))
                drive = _read_drive(plugin, 'diff' if filename == DIFF_DRIVE else 'skid', source, lines, warnings)
            else:
                warnings.append('%s: plugin %s is not simulated' % (where(source, lines, plugin), filename))
        for sensor in gz.findall('sensor'):
            if sensor.get('type') in ('ray', 'gpu_ray'):
                lasers.append((gz.get('reference', ''), sensor))
            else:
                warnings.append('%s: sensor type "%s" is not simulated' % (where(source, lines, sensor), sensor.get('type')))
    if drive is None:
        raise XmlError('%s: no drive plugin (%s or %s) in any <gazebo> tag: the robot could not move'
                       % (where(source, lines, root), DIFF_DRIVE, SKID_STEER))
    if drive.robot_base_frame not in link_tf:
        raise XmlError('%s: robotBaseFrame "%s" is not a link of the robot (links: %s)'
                       % (where(source, lines, root), drive.robot_base_frame, ', '.join(sorted(link_tf))))
    base_inv = np.linalg.inv(link_tf[drive.robot_base_frame])
    laser_specs = [_read_laser(ref, s, base_inv, link_tf, source, lines, warnings) for ref, s in lasers]
    footprint, (floor_z, top_z) = _footprint(links, link_tf, base_inv, source, lines, warnings)
    for laser in laser_specs:
        laser.height = laser.z_in_base - floor_z
    return RobotSpec(name=root.get('name', 'robot'), drive=drive, lasers=laser_specs, footprint=footprint,
                     warnings=warnings, wheels=_wheel_joints(root, drive, source, lines, warnings),
                     height=top_z - floor_z)


def _wheel_joints(root, drive: DriveSpec, source, lines, warnings) -> List[WheelJoint]:
    joints = {j.get('name'): j for j in root.findall('joint')}
    out = []
    for k, name in enumerate(drive.wheel_joints):
        j = joints.get(name)
        if j is None:
            warnings.append('%s: wheel joint "%s" named by the drive plugin is not in the URDF'
                            % (where(source, lines, root), name))
            continue
        origin = j.find('origin')
        xyz = floats(origin.get('xyz', '0 0 0'), 3, name) if origin is not None else [0, 0, 0]
        rpy = floats(origin.get('rpy', '0 0 0'), 3, name) if origin is not None else [0, 0, 0]
        axis_el = j.find('axis')
        axis = np.array(floats(axis_el.get('xyz', '1 0 0'), 3, name) if axis_el is not None else [1, 0, 0])
        out.append(WheelJoint(name=name, parent=j.find('parent').get('link'), child=j.find('child').get('link'),
                              origin=from_xyz_rpy(xyz, rpy), axis=axis / np.linalg.norm(axis), side=k % 2))
    return out


def _link_transforms(root, links, source, lines) -> Dict[str, np.ndarray]:
    """Each link's transform in the root link's frame, at zero joint positions."""
    children = {}
    for j in root.findall('joint'):
        parent, child = j.find('parent'), j.find('child')
        if parent is None or child is None:
            raise XmlError('%s: a joint needs <parent link=""> and <child link="">' % where(source, lines, j))
        origin = j.find('origin')
        xyz = floats(origin.get('xyz', '0 0 0'), 3, where(source, lines, j) + ' origin xyz') if origin is not None else [0, 0, 0]
        rpy = floats(origin.get('rpy', '0 0 0'), 3, where(source, lines, j) + ' origin rpy') if origin is not None else [0, 0, 0]
        children.setdefault(parent.get('link'), []).append((child.get('link'), from_xyz_rpy(xyz, rpy)))
    child_names = {c for cs in children.values() for c, _ in cs}
    roots = [n for n in links if n not in child_names]
    if len(roots) != 1:
        raise XmlError('%s: the links form %d trees (roots: %s); URDF needs exactly one'
                       % (where(source, lines, root), len(roots), ', '.join(roots)))
    out = {roots[0]: np.eye(4)}
    stack = [roots[0]]
    while stack:
        name = stack.pop()
        for child, tf in children.get(name, []):
            out[child] = out[name] @ tf
            stack.append(child)
    return out


def _read_drive(plugin, kind, source, lines, warnings) -> DriveSpec:
    spec = DriveSpec(kind=kind)
    if kind == 'skid':
        spec.wheel_separation, spec.odometry_source, spec.publish_odom_tf = 0.4, 'encoder', False
    here = where(source, lines, plugin)
    joints = {}
    for el in plugin:
        tag, text = el.tag, (el.text or '').strip()
        if tag in IGNORED_DRIVE_TAGS:
            continue
        if tag not in DRIVE_TAGS[kind]:
            warnings.append('%s: <%s> is not a parameter of %s; ignored' % (here, tag, plugin.get('filename')))
            continue
        try:
            if tag == 'commandTopic':
                spec.command_topic = text
            elif tag == 'odometryTopic':
                spec.odometry_topic = text
            elif tag == 'odometryFrame':
                spec.odometry_frame = text
            elif tag == 'robotBaseFrame':
                spec.robot_base_frame = text
            elif tag == 'wheelSeparation':
                spec.wheel_separation = float(text)
            elif tag == 'wheelDiameter':
                spec.wheel_diameter = float(text)
            elif tag == 'wheelAcceleration':
                spec.wheel_acceleration = float(text)
            elif tag == 'updateRate':
                spec.update_rate = float(text)
            elif tag == 'odometrySource':
                if text.lower() not in ('world', 'encoder', '0', '1'):
                    raise ValueError('odometrySource must be world or encoder')
                spec.odometry_source = 'encoder' if text.lower() in ('encoder', '0') else 'world'
            elif tag in ('publishOdomTF', 'broadcastTF'):
                spec.publish_odom_tf = _bool(text)
            elif tag == 'publishWheelTF':
                spec.publish_wheel_tf = _bool(text)
            elif tag.endswith('Joint'):
                joints[tag] = text
            elif tag.startswith('covariance_'):
                spec.covariance[['covariance_x', 'covariance_y', 'covariance_yaw'].index(tag)] = float(text)
        except ValueError as e:
            raise XmlError('%s: <%s>%s</%s>: %s' % (here, tag, text, tag, e)) from None
    order = ['leftJoint', 'rightJoint'] if kind == 'diff' else ['leftFrontJoint', 'rightFrontJoint',
                                                                 'leftRearJoint', 'rightRearJoint']
    spec.wheel_joints = [joints[k] for k in order if k in joints]
    for name, value in (('wheelSeparation', spec.wheel_separation), ('wheelDiameter', spec.wheel_diameter),
                        ('updateRate', spec.update_rate)):
        if not value > 0:
            raise XmlError('%s: <%s> must be positive, got %g' % (here, name, value))
    return spec


def _read_laser(reference, sensor, base_inv, link_tf, source, lines, warnings) -> LaserSpec:
    here = where(source, lines, sensor)
    if reference not in link_tf:
        raise XmlError('%s: <gazebo reference="%s"> is not a link of the robot' % (here, reference))
    spec = LaserSpec(name=sensor.get('name', 'laser'), link=reference, frame_id=reference)
    pose_text = child_text(sensor, 'pose')
    sensor_tf = np.eye(4)
    if pose_text:
        v = floats(pose_text, 6, here + ' <pose>')
        sensor_tf = from_xyz_rpy(v[:3], v[3:])
    in_base = base_inv @ link_tf[reference] @ sensor_tf
    spec.pose_in_base = planar(in_base)
    spec.z_in_base = float(in_base[2, 3])

    def number(path, default):
        text = child_text(sensor, path)
        if text is None:
            return default
        return floats(text, 1, '%s <%s>' % (here, path))[0]

    spec.update_rate = number('update_rate', spec.update_rate)
    samples = number('ray/scan/horizontal/samples', spec.samples)
    resolution = number('ray/scan/horizontal/resolution', 1.0)
    spec.samples = int(round(samples * resolution))
    spec.angle_min = number('ray/scan/horizontal/min_angle', spec.angle_min)
    spec.angle_max = number('ray/scan/horizontal/max_angle', spec.angle_max)
    spec.range_min = number('ray/range/min', spec.range_min)
    spec.range_max = number('ray/range/max', spec.range_max)
    spec.range_resolution = number('ray/range/resolution', 0.0)
    noise = sensor.find('ray/noise')
    if noise is not None:
        if child_text(noise, 'type', 'gaussian') != 'gaussian':
            warnings.append('%s: only gaussian laser noise is simulated' % here)
        spec.noise_stddev = number('ray/noise/stddev', 0.0)
    plugin = sensor.find('plugin')
    if plugin is None or plugin.get('filename') not in LASER_PLUGINS:
        warnings.append('%s: no %s plugin: the scan is simulated but published on "%s"'
                        % (here, ' or '.join(LASER_PLUGINS), spec.topic))
    else:
        spec.topic = child_text(plugin, 'topicName', spec.topic)
        spec.frame_id = child_text(plugin, 'frameName', spec.frame_id)
    if spec.samples < 1:
        raise XmlError('%s: the laser has %d samples; it needs at least 1' % (here, spec.samples))
    if not spec.range_max > spec.range_min >= 0:
        raise XmlError('%s: range max (%g) must exceed range min (%g) >= 0' % (here, spec.range_max, spec.range_min))
    if not spec.angle_max >= spec.angle_min:
        raise XmlError('%s: max_angle (%g) below min_angle (%g)' % (here, spec.angle_max, spec.angle_min))
    if not spec.update_rate > 0:
        raise XmlError('%s: update_rate must be positive, got %g' % (here, spec.update_rate))
    return spec


def _footprint(links, link_tf, base_inv, source, lines, warnings):
    """(convex hull of every collision geometry projected on the base frame's xy plane, (lowest,
    highest) z [m] of that geometry in the base frame: the floor the wheels stand on and the top)."""
    points = []
    circle = np.linspace(0, 2 * math.pi, 16, endpoint=False)
    for name, link in links.items():
        for col in link.findall('collision'):
            origin = col.find('origin')
            tf = np.eye(4)
            if origin is not None:
                tf = from_xyz_rpy(floats(origin.get('xyz', '0 0 0'), 3, where(source, lines, col) + ' origin xyz'),
                                  floats(origin.get('rpy', '0 0 0'), 3, where(source, lines, col) + ' origin rpy'))
            tf = base_inv @ link_tf[name] @ tf
            geom = col.find('geometry')
            g = geom[0] if geom is not None and len(geom) else None
            if g is None:
                continue
            if g.tag == 'box':
                sx, sy, sz = floats(g.get('size', ''), 3, where(source, lines, g) + ' size')
                local = np.array([[a * sx / 2, b * sy / 2, c * sz / 2] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
            elif g.tag in ('cylinder', 'sphere'):
                r = float(g.get('radius', '0'))
                h = float(g.get('length', '0')) if g.tag == 'cylinder' else 0.0
                ring = np.stack([r * np.cos(circle), r * np.sin(circle)], axis=1)
                local = np.vstack([np.hstack([ring, np.full((16, 1), z)]) for z in (-h / 2, h / 2)])
            else:
                warnings.append('%s: <%s> collision is left out of the footprint' % (where(source, lines, g), g.tag))
                continue
            if g.tag == 'sphere':
                local = np.vstack([local, [[0, 0, -r], [0, 0, r]]])
            points.append((tf[:3, :3] @ local.T).T + tf[:3, 3])
    if not points:
        raise XmlError('%s: no link has box, cylinder or sphere collision geometry: no footprint to collide with'
                       % source)
    p = np.vstack(points)
    return convex_hull(p[:, :2]), (float(p[:, 2].min()), float(p[:, 2].max()))
