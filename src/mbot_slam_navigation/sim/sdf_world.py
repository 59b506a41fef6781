"""Reads Gazebo SDF .world files into the 2D shapes the simulator collides with and sees.

Models' collision geometry is kept: boxes and cylinders (spheres as circles), their poses composed
model -> link -> collision in the plane (x, y, yaw; z, roll and pitch dropped). A world's <state>
block overrides model poses (and link poses, which it gives in the world frame). Includes of
model://ground_plane and model://sun are skipped; other includes, meshes and unknown geometry are
reported as warnings naming the element and line, never dropped silently.

Actors (people, Gazebo's <actor>) are read with their <script>: <loop> (default true), <delay_start>
(0 s), <auto_start> (true) and the <trajectory> elements, played one after the other in file order,
each <waypoint> a <time> [s from the trajectory's start] and a <pose> in the world frame. Between
waypoints the person moves in a straight line at constant speed (Gazebo interpolates a spline; for
waypoints a room apart the difference is centimetres). An actor without a script stands at its <pose>.
Gazebo's actors have no collision; here a person is a cylinder that lasers see and robots touch: the
radius of a cylinder collision in the actor's <link> if it has one, else PERSON_RADIUS. Skins and
animations (meshes) are ignored without a warning: they are how a person looks, not where.
"""
import math
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

from mbot_slam_navigation.transforms import from_xyz_rpy, planar
from mbot_slam_navigation.sim.xmlutil import XmlError, child_text, floats, parse_xml, where

SKIPPED_INCLUDES = ('model://ground_plane', 'model://sun')
PERSON_RADIUS = 0.25  # [m] a person seen from above at a laser's height, shoulders to elbows


@dataclass
class Waypoint:
    time: float               # [s] since the script started (trajectories concatenated)
    x: float                  # [m] world frame
    y: float
    yaw: float = 0.0          # [rad]


@dataclass
class Actor:
    """A person: stands at (x, y, yaw) or follows `waypoints`, looping if `loop`."""
    name: str
    x: float
    y: float
    yaw: float = 0.0
    radius: float = PERSON_RADIUS
    waypoints: List[Waypoint] = field(default_factory=list)
    loop: bool = True
    delay_start: float = 0.0  # [s] of simulated time before the script starts
    auto_start: bool = True   # False: stands at its pose (Gazebo waits for a trigger that nothing here sends)

    @property
    def duration(self) -> float:
        return self.waypoints[-1].time if self.waypoints else 0.0

    def pose_at(self, t: float):
        """(x, y, yaw) after `t` s of its script (before delay_start is taken off)."""
        w = self.waypoints
        if not w or not self.auto_start:
            return self.x, self.y, self.yaw
        if self.loop and self.duration > 0.0:
            t = math.fmod(t, self.duration)
        if t <= w[0].time:
            return w[0].x, w[0].y, w[0].yaw
        for a, b in zip(w, w[1:]):
            if t <= b.time:
                f = (t - a.time) / (b.time - a.time) if b.time > a.time else 1.0
                dyaw = math.atan2(math.sin(b.yaw - a.yaw), math.cos(b.yaw - a.yaw))
                return a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), a.yaw + f * dyaw
        return w[-1].x, w[-1].y, w[-1].yaw

    def moved(self, x: float, y: float, yaw: float) -> 'Actor':
        """This actor with its pose and every waypoint put into the frame (x, y, yaw) [m, rad]."""
        c, s = math.cos(yaw), math.sin(yaw)
        tf = lambda px, py: (x + c * px - s * py, y + s * px + c * py)  # noqa: E731
        ax, ay = tf(self.x, self.y)
        return Actor(self.name, ax, ay, self.yaw + yaw, self.radius,
                     [Waypoint(p.time, *tf(p.x, p.y), p.yaw + yaw) for p in self.waypoints],
                     self.loop, self.delay_start, self.auto_start)


@dataclass
class Shape:
    """A collision shape in the world frame: a box (size_x, size_y) or a circle (radius)."""
    kind: str                 # 'box' or 'circle'
    x: float                  # [m] centre
    y: float
    yaw: float = 0.0          # [rad]
    size_x: float = 0.0       # [m] box only
    size_y: float = 0.0
    radius: float = 0.0       # [m] circle only
    name: str = ''            # model/link/collision, for messages


@dataclass
class World:
    name: str
    shapes: List[Shape] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    actors: List[Actor] = field(default_factory=list)

    def bounds(self):
        """(xmin, ymin, xmax, ymax) [m] of all shapes, or None for an empty world."""
        if not self.shapes:
            return None
        pts = []
        for s in self.shapes:
            if s.kind == 'circle':
                pts += [(s.x - s.radius, s.y - s.radius), (s.x + s.radius, s.y + s.radius)]
                continue
            c, si = math.cos(s.yaw), math.sin(s.yaw)
            pts += [(s.x + c * a * s.size_x / 2 - si * b * s.size_y / 2, s.y + si * a * s.size_x / 2 + c * b * s.size_y / 2)
                    for a in (-1, 1) for b in (-1, 1)]
        a = np.array(pts)
        return tuple(a.min(axis=0)) + tuple(a.max(axis=0))


def _pose(element, source, lines) -> np.ndarray:
    text = child_text(element, 'pose')
    if text is None:
        return np.eye(4)
    v = floats(text, 6, '%s <pose>' % where(source, lines, element))
    return from_xyz_rpy(v[:3], v[3:])


def load_world(path: str) -> World:
    """Reads an SDF world file; raises XmlError (file, line, element) when it cannot be used."""
    if not os.path.isfile(path):
        raise XmlError('world file %s does not exist' % path)
    with open(path, encoding='utf-8') as f:
        return parse_world(f.read(), path)


def parse_world(text: str, source: str = '<string>') -> World:
    root, lines = parse_xml(text, source)
    if root.tag != 'sdf':
        raise XmlError('%s: the root element is <%s>, expected <sdf>' % (where(source, lines, root), root.tag))
    world_el = root.find('world')
    if world_el is None:
        raise XmlError('%s: no <world> element' % where(source, lines, root))
    world = World(name=world_el.get('name', 'default'))

    # Poses from <state>: model name -> model pose, and (model, link) -> link pose in the world.
    state_models: Dict[str, np.ndarray] = {}
    state_links: Dict[tuple, np.ndarray] = {}
    state = world_el.find('state')
    if state is not None:
        for m in state.findall('model'):
            if m.find('pose') is not None:
                state_models[m.get('name')] = _pose(m, source, lines)
            for link in m.findall('link'):
                if link.find('pose') is not None:
                    state_links[(m.get('name'), link.get('name'))] = _pose(link, source, lines)

    for inc in world_el.findall('include'):
        uri = child_text(inc, 'uri', '')
        if uri not in SKIPPED_INCLUDES:
            world.warnings.append('%s: include of "%s" is not supported; it is left out of the world'
                                  % (where(source, lines, inc), uri))
    for model in world_el.findall('model'):
        _read_model(model, np.eye(4), source, lines, state_models, state_links, world, top_level=True)
    names = set()
    for el in world_el.findall('actor'):
        actor = read_actor(el, source, lines, world.warnings)
        if actor.name in names:
            raise XmlError('%s: a second actor named "%s"' % (where(source, lines, el), actor.name))
        names.add(actor.name)
        world.actors.append(actor)
    return world


def parse_actors(text: str, source: str = '<string>') -> List[Actor]:
    """The <actor> elements of an SDF document (<sdf><actor>, or inside its <world>), as
    gazebo_ros's spawn_sdf_model receives them; raises XmlError when there is none."""
    root, lines = parse_xml(text, source)
    holder = root.find('world') if root.find('world') is not None else root
    elements = [root] if root.tag == 'actor' else holder.findall('actor')
    if not elements:
        raise XmlError('%s: no <actor> element (this simulator spawns people from SDF; robots come as URDF '
                       'through spawn_urdf_model)' % where(source, lines, root))
    warnings: List[str] = []
    return [read_actor(el, source, lines, warnings) for el in elements]


def read_actor(el, source, lines, warnings: List[str]) -> Actor:
    here = where(source, lines, el)
    name = el.get('name')
    if not name:
        raise XmlError('%s: an actor needs a name attribute' % here)
    x, y, yaw = planar(_pose(el, source, lines))
    radius = PERSON_RADIUS
    for cyl in el.findall('link/collision/geometry/cylinder'):
        radius = floats(child_text(cyl, 'radius', ''), 1, '%s <cylinder><radius>' % where(source, lines, cyl))[0]
        if radius <= 0:
            raise XmlError('%s: radius must be positive, got %g' % (where(source, lines, cyl), radius))
    actor = Actor(name, x, y, yaw, radius)
    script = el.find('script')
    if script is None:
        return actor

    def flag(tag, default):
        text = child_text(script, tag)
        if text is None:
            return default
        if text.lower() not in ('true', 'false', '1', '0'):
            raise XmlError('%s <%s>: expected true or false, got "%s"' % (here, tag, text))
        return text.lower() in ('true', '1')

    actor.loop, actor.auto_start = flag('loop', True), flag('auto_start', True)
    delay = child_text(script, 'delay_start')
    actor.delay_start = floats(delay, 1, '%s <delay_start>' % here)[0] if delay is not None else 0.0
    offset = 0.0
    for traj in script.findall('trajectory'):
        t_here = where(source, lines, traj)
        last = None
        for wp in traj.findall('waypoint'):
            w_here = where(source, lines, wp)
            t_text, p_text = child_text(wp, 'time'), child_text(wp, 'pose')
            if t_text is None or p_text is None:
                raise XmlError('%s: a waypoint needs <time> and <pose>' % w_here)
            t = floats(t_text, 1, '%s <time>' % w_here)[0]
            if t < 0 or (last is not None and t < last):
                raise XmlError('%s: waypoint times must not decrease (%g after %g)' % (w_here, t, last or 0.0))
            last = t
            px, py, pyaw = planar(_pose(wp, source, lines))
            actor.waypoints.append(Waypoint(offset + t, px, py, pyaw))
        if last is None:
            warnings.append('%s: a trajectory without waypoints; skipped' % t_here)
        else:
            offset += last
    if actor.waypoints and actor.waypoints[-1].time <= 0.0 and len(actor.waypoints) > 1:
        raise XmlError('%s: the script\'s waypoints all have time 0' % here)
    if actor.waypoints:
        actor.x, actor.y, actor.yaw = actor.waypoints[0].x, actor.waypoints[0].y, actor.waypoints[0].yaw
    return actor


def _read_model(model, parent: np.ndarray, source, lines, state_models, state_links, world: World,
                top_level: bool) -> None:
    name = model.get('name', '?')
    model_pose = state_models.get(name) if top_level and name in state_models else parent @ _pose(model, source, lines)
    for nested in model.findall('model'):
        _read_model(nested, model_pose, source, lines, state_models, state_links, world, top_level=False)
    for link in model.findall('link'):
        link_name = link.get('name', '?')
        link_pose = state_links.get((name, link_name))
        if link_pose is None:
            link_pose = model_pose @ _pose(link, source, lines)
        for col in link.findall('collision'):
            shape = _read_geometry(col, link_pose @ _pose(col, source, lines), source, lines, world)
            if shape is not None:
                shape.name = '%s/%s/%s' % (name, link_name, col.get('name', '?'))
                world.shapes.append(shape)


def _read_geometry(col, pose: np.ndarray, source, lines, world: World) -> Optional[Shape]:
    geom = col.find('geometry')
    here = where(source, lines, col)
    if geom is None or len(geom) == 0:
        world.warnings.append('%s: no <geometry>; collision left out' % here)
        return None
    g = geom[0]
    x, y, yaw = planar(pose)
    if g.tag == 'box':
        sx, sy, _ = floats(child_text(g, 'size', ''), 3, '%s <box><size>' % here)
        if sx <= 0 or sy <= 0:
            raise XmlError('%s: box size must be positive, got %g x %g' % (here, sx, sy))
        return Shape('box', x, y, yaw, size_x=sx, size_y=sy)
    if g.tag in ('cylinder', 'sphere'):
        r = child_text(g, 'radius')
        if r is None:
            raise XmlError('%s: <%s> without <radius>' % (here, g.tag))
        radius = floats(r, 1, '%s <%s><radius>' % (here, g.tag))[0]
        if radius <= 0:
            raise XmlError('%s: %s radius must be positive, got %g' % (here, g.tag, radius))
        return Shape('circle', x, y, yaw, radius=radius)
    if g.tag == 'plane':
        return None  # a ground plane: the floor the robot drives on, not an obstacle
    world.warnings.append('%s: <%s> geometry is not supported in 2D; collision left out' % (where(source, lines, g), g.tag))
    return None
