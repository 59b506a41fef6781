"""Reads Gazebo SDF .world files into the 2D shapes the simulator collides with and sees.

Models' collision geometry is kept: boxes and cylinders (spheres as circles), their poses composed
model -> link -> collision in the plane (x, y, yaw; z, roll and pitch dropped). A world's <state>
block overrides model poses (and link poses, which it gives in the world frame). Includes of
model://ground_plane and model://sun are skipped; other includes, meshes and unknown geometry are
reported as warnings naming the element and line, never dropped silently.
"""
import math
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

from mbot_slam_navigation.transforms import from_xyz_rpy, planar
from mbot_slam_navigation.sim.xmlutil import XmlError, child_text, floats, parse_xml, where

SKIPPED_INCLUDES = ('model://ground_plane', 'model://sun')


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
    return world


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
