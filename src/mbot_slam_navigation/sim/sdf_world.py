"""Reads worlds into the 2D shapes the simulator collides with and sees: Gazebo SDF .world files,
and map_server YAML maps (load_world picks by the file's extension; sim/map_world.py).

Models' collision geometry is kept: boxes and cylinders (spheres as circles) and <image> geometry
(a grayscale picture extruded into walls, as Gazebo's: pixel column c, row r covers [c, c+1) x
[r, r+1) times <scale> metres in the model frame, so rows run along +y; a pixel whose mean of R, G
and B is at most <threshold> (default 200) is solid, up to <height> (1 m) from the collision's z;
<granularity> g merges blocks of about sqrt(g) pixels, solid if any pixel is). Poses are composed
model -> link -> collision in 3D; each shape keeps its planar pose (x, y, yaw) and the heights it
spans [m above the floor]. Shapes wholly under the floor (ground planes, foundations) are left out;
the simulator decides per robot what a laser's plane cuts and what stops a body (a lintel above a
door stops neither). A world's <state> block overrides model poses (and link poses, which it gives
in the world frame).

<include> of model://NAME is found as Gazebo finds it: in each folder of GAZEBO_MODEL_PATH, then
~/.gazebo/models, a folder NAME with model.config naming the SDF file (else model.sdf); its <name>
and <pose> override the model's. model://ground_plane and model://sun are skipped. A model whose
collisions are meshes gets one warning naming it and what was left out; unknown geometry and models
not found are warnings naming the element and line, never dropped silently.

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
from typing import Dict, List, Optional, Tuple

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
    """A collision shape in the world frame: a box (size_x, size_y), a circle (radius) or a grid
    (solid cells of a raster), spanning heights z_lo..z_hi [m above the floor]."""
    kind: str                 # 'box', 'circle' or 'grid'
    x: float                  # [m] centre; for a grid the outer corner of cell (row 0, col 0)
    y: float
    yaw: float = 0.0          # [rad]
    size_x: float = 0.0       # [m] box only
    size_y: float = 0.0
    radius: float = 0.0       # [m] circle only
    name: str = ''            # model/link/collision, for messages
    z_lo: float = -math.inf   # [m] the heights it spans
    z_hi: float = math.inf
    cells: Optional[np.ndarray] = None  # grid only: (rows, cols) bool, row r / col c covers [c, c+1) x [r, r+1)
    resolution: float = 0.0   # [m] grid only: a cell's edge, along the grid's x (cols) and y (rows)

    def blocks(self, z_lo: float, z_hi: float) -> bool:
        """True if the shape's heights overlap z_lo..z_hi (a body from z_lo to z_hi is stopped by it)."""
        return self.z_lo < z_hi and z_lo < self.z_hi

    def corners(self) -> np.ndarray:
        """(N, 2) [m] world points that bound the shape: a box's corners, a circle's bounding square, a
        grid's solid cells' corners (all four of every solid cell, or none if it has none)."""
        c, si = math.cos(self.yaw), math.sin(self.yaw)
        if self.kind == 'circle':
            r = self.radius
            return np.array([(self.x + a * r, self.y + b * r) for a in (-1, 1) for b in (-1, 1)])
        if self.kind == 'box':
            local = np.array([(a * self.size_x / 2, b * self.size_y / 2) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
        else:
            rows, cols = np.nonzero(self.cells)
            if not len(rows):
                return np.zeros((0, 2))
            local = np.array([(cols.min(), rows.min()), (cols.max() + 1, rows.min()), (cols.max() + 1, rows.max() + 1),
                              (cols.min(), rows.max() + 1)], float) * self.resolution
        return np.column_stack([self.x + c * local[:, 0] - si * local[:, 1], self.y + si * local[:, 0] + c * local[:, 1]])


@dataclass
class World:
    name: str
    shapes: List[Shape] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    actors: List[Actor] = field(default_factory=list)

    def bounds(self):
        """(xmin, ymin, xmax, ymax) [m] of all shapes, or None for an empty world."""
        pts = [s.corners() for s in self.shapes]
        pts = [p for p in pts if len(p)]
        if not pts:
            return None
        a = np.vstack(pts)
        return tuple(float(v) for v in a.min(axis=0)) + tuple(float(v) for v in a.max(axis=0))

    def blocking(self, z_lo: float, z_hi: float) -> 'World':
        """This world with only the shapes whose heights overlap z_lo..z_hi [m]: what a body spanning
        those heights meets, and (within them) what its laser sees."""
        return World(self.name, [s for s in self.shapes if s.blocks(z_lo, z_hi)], self.warnings, self.actors)


def _pose(element, source, lines) -> np.ndarray:
    text = child_text(element, 'pose')
    if text is None:
        return np.eye(4)
    v = floats(text, 6, '%s <pose>' % where(source, lines, element))
    return from_xyz_rpy(v[:3], v[3:])


def load_world(path: str, map_unknown: str = 'solid') -> World:
    """Reads an SDF world file, or a map_server YAML map (.yaml, .yml: sim/map_world.py, whose unknown
    cells are `map_unknown`: 'solid' or 'free'); raises XmlError (file, line, element) or MapFileError
    (file, key) when it cannot be used."""
    if not os.path.isfile(path):
        raise XmlError('world file %s does not exist' % path)
    if path.lower().endswith(('.yaml', '.yml')):
        from mbot_slam_navigation.sim.map_world import load_map_world
        return load_map_world(path, map_unknown)
    with open(path, encoding='utf-8') as f:
        return parse_world(f.read(), path)


def model_path() -> List[str]:
    """The folders searched for model://NAME, in Gazebo's order: GAZEBO_MODEL_PATH, then ~/.gazebo/models."""
    folders = [p for p in os.environ.get('GAZEBO_MODEL_PATH', '').split(':') if p]
    return folders + [os.path.join(os.path.expanduser('~'), '.gazebo', 'models')]


def find_model(name: str) -> Optional[str]:
    """The SDF file of model://NAME (model.config's <sdf>, the newest version if several; else
    model.sdf), or None if no folder of model_path() has it."""
    for folder in model_path():
        d = os.path.join(folder, name)
        config = os.path.join(d, 'model.config')
        if os.path.isfile(config):
            try:
                with open(config, encoding='utf-8') as f:
                    root, _ = parse_xml(f.read(), config)
                files = sorted(root.findall('sdf'), key=lambda e: [int(v) for v in e.get('version', '0').split('.')
                                                                   if v.isdigit()])
                if files and files[-1].text and os.path.isfile(os.path.join(d, files[-1].text.strip())):
                    return os.path.join(d, files[-1].text.strip())
            except (OSError, XmlError):
                pass
        if os.path.isfile(os.path.join(d, 'model.sdf')):
            return os.path.join(d, 'model.sdf')
    return None


def resolve_uri(uri: str, base_dir: str) -> Tuple[Optional[str], str]:
    """(path, '') of a file URI as Gazebo resolves it: model://NAME/rest through model_path(),
    file://PATH, or a path relative to `base_dir` (the file that names it); (None, why) otherwise."""
    if uri.startswith('model://'):
        name, _, rest = uri[len('model://'):].partition('/')
        for folder in model_path():
            candidate = os.path.join(folder, name, rest)
            if os.path.isfile(candidate):
                return candidate, ''
        return None, 'not found in GAZEBO_MODEL_PATH or ~/.gazebo/models (searched: %s)' % ', '.join(model_path())
    if uri.startswith('file://'):
        uri = uri[len('file://'):]
    path = uri if os.path.isabs(uri) else os.path.join(base_dir, uri)
    return (path, '') if os.path.isfile(path) else (None, 'no such file %s' % path)


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

    ctx = _Context(source, lines, state_models, state_links, world, os.path.dirname(os.path.abspath(source)))
    for inc in world_el.findall('include'):
        _read_include(inc, np.eye(4), ctx, top_level=True, seen=())
    for model in world_el.findall('model'):
        _read_model(model, np.eye(4), ctx, top_level=True)
    world.shapes = [s for s in world.shapes if s.z_hi > 0.0]  # under the floor: ground planes, foundations
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


@dataclass
class _Context:
    """Where elements come from (for messages and relative URIs) and what is being built."""
    source: str
    lines: Dict
    state_models: Dict
    state_links: Dict
    world: World
    base_dir: str             # folder of the file being read: URIs relative to it


def _read_include(inc, parent: np.ndarray, ctx: _Context, top_level: bool, seen: Tuple[str, ...]) -> None:
    """An <include> of model://NAME: the model's SDF read in place, with the include's name and pose."""
    here = where(ctx.source, ctx.lines, inc)
    uri = child_text(inc, 'uri', '')
    if uri in SKIPPED_INCLUDES:
        return
    if not uri.startswith('model://'):
        ctx.world.warnings.append('%s: include of "%s": only model:// URIs are understood; left out of the world'
                                  % (here, uri))
        return
    name = uri[len('model://'):].strip('/')
    if name in seen:
        raise XmlError('%s: model://%s includes itself' % (here, name))
    path = find_model(name)
    if path is None:
        ctx.world.warnings.append('%s: model://%s not found in GAZEBO_MODEL_PATH or ~/.gazebo/models (searched: %s); '
                                  'left out of the world' % (here, name, ', '.join(model_path())))
        return
    with open(path, encoding='utf-8') as f:
        root, lines = parse_xml(f.read(), path)
    model = root.find('model') if root.tag == 'sdf' else (root if root.tag == 'model' else None)
    if model is None:
        ctx.world.warnings.append('%s: %s has no <model>; model://%s left out of the world' % (here, path, name))
        return
    if child_text(inc, 'name'):
        model.set('name', child_text(inc, 'name'))
    pose = _pose(inc, ctx.source, ctx.lines) if inc.find('pose') is not None else None
    inner = _Context(path, lines, ctx.state_models, ctx.state_links, ctx.world, os.path.dirname(path))
    _read_model(model, parent, inner, top_level, pose_override=pose, seen=seen + (name,))


def _read_model(model, parent: np.ndarray, ctx: _Context, top_level: bool, pose_override=None,
                seen: Tuple[str, ...] = ()) -> None:
    name = model.get('name', '?')
    before = len(ctx.world.shapes)
    own = pose_override if pose_override is not None else _pose(model, ctx.source, ctx.lines)
    model_pose = ctx.state_models[name] if top_level and name in ctx.state_models else parent @ own
    for nested in model.findall('model'):
        _read_model(nested, model_pose, ctx, top_level=False, seen=seen)
    for inc in model.findall('include'):
        _read_include(inc, model_pose, ctx, top_level=False, seen=seen)
    left_out: List[str] = []
    for link in model.findall('link'):
        link_name = link.get('name', '?')
        link_pose = ctx.state_links.get((name, link_name))
        if link_pose is None:
            link_pose = model_pose @ _pose(link, ctx.source, ctx.lines)
        for col in link.findall('collision'):
            shape = _read_geometry(col, link_pose @ _pose(col, ctx.source, ctx.lines), ctx, left_out)
            if shape is not None:
                shape.name = '%s/%s/%s' % (name, link_name, col.get('name', '?'))
                ctx.world.shapes.append(shape)
    kept = len(ctx.world.shapes) - before  # its own and its nested models' and includes'
    if left_out:
        kinds = sorted(set(left_out))
        what = '%d <%s> collision%s' % (len(left_out), '>, <'.join(kinds), '' if len(left_out) == 1 else 's')
        if kept:
            ctx.world.warnings.append('%s: %s left out (not simulated in 2D); its %d other collision%s kept'
                                      % (where(ctx.source, ctx.lines, model), what, kept, '' if kept == 1 else 's'))
        else:
            ctx.world.warnings.append('%s: %s left out (not simulated in 2D): the model is not in the world, '
                                      'robots and lasers pass through where it stands'
                                      % (where(ctx.source, ctx.lines, model), what))


def _heights(pose: np.ndarray, half_extent: np.ndarray) -> Tuple[float, float]:
    """[m] lowest and highest z of a box of half sizes `half_extent` (its own axes) at `pose`."""
    reach = float(np.abs(pose[2, :3]) @ half_extent)
    return float(pose[2, 3]) - reach, float(pose[2, 3]) + reach


def _read_geometry(col, pose: np.ndarray, ctx: _Context, left_out: List[str]) -> Optional[Shape]:
    source, lines, world = ctx.source, ctx.lines, ctx.world
    geom = col.find('geometry')
    here = where(source, lines, col)
    if geom is None or len(geom) == 0:
        world.warnings.append('%s: no <geometry>; collision left out' % here)
        return None
    g = geom[0]
    x, y, yaw = planar(pose)
    if g.tag == 'box':
        sx, sy, sz = floats(child_text(g, 'size', ''), 3, '%s <box><size>' % here)
        if sx <= 0 or sy <= 0:
            raise XmlError('%s: box size must be positive, got %g x %g' % (here, sx, sy))
        z_lo, z_hi = _heights(pose, np.array([sx, sy, max(sz, 0.0)]) / 2)
        return Shape('box', x, y, yaw, size_x=sx, size_y=sy, z_lo=z_lo, z_hi=z_hi)
    if g.tag in ('cylinder', 'sphere'):
        r = child_text(g, 'radius')
        if r is None:
            raise XmlError('%s: <%s> without <radius>' % (here, g.tag))
        radius = floats(r, 1, '%s <%s><radius>' % (here, g.tag))[0]
        if radius <= 0:
            raise XmlError('%s: %s radius must be positive, got %g' % (here, g.tag, radius))
        length = floats(child_text(g, 'length', '1'), 1, '%s <cylinder><length>' % here)[0] if g.tag == 'cylinder' else 2 * radius
        z_lo, z_hi = _heights(pose, np.array([radius, radius, length / 2]))
        return Shape('circle', x, y, yaw, radius=radius, z_lo=z_lo, z_hi=z_hi)
    if g.tag == 'image':
        return _read_image(g, pose, ctx)
    if g.tag == 'plane':
        return None  # a ground plane: the floor the robot drives on, not an obstacle
    if g.tag in ('mesh', 'heightmap', 'polyline'):
        left_out.append(g.tag)
        return None
    world.warnings.append('%s: <%s> geometry is not supported in 2D; collision left out' % (where(source, lines, g), g.tag))
    return None


def _read_image(g, pose: np.ndarray, ctx: _Context) -> Shape:
    """SDF <image> geometry: the picture extruded into a grid shape (module docstring)."""
    import cv2
    here = where(ctx.source, ctx.lines, g)
    uri = child_text(g, 'uri')
    if not uri:
        raise XmlError('%s: <image> without <uri>' % here)
    path, why = resolve_uri(uri, ctx.base_dir)
    if path is None:
        raise XmlError('%s <uri>%s</uri>: %s' % (here, uri, why))

    def number(tag, default):
        text = child_text(g, tag)
        return default if text is None else floats(text, 1, '%s <%s>' % (here, tag))[0]

    scale, threshold, height = number('scale', 1.0), number('threshold', 200.0), number('height', 1.0)
    granularity = int(number('granularity', 1.0))
    if not scale > 0:
        raise XmlError('%s <scale>: must be positive [m per pixel], got %g' % (here, scale))
    if not height > 0:
        raise XmlError('%s <height>: must be positive [m], got %g' % (here, height))
    picture = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if picture is None:
        raise XmlError('%s <uri>%s</uri>: %s is not an image OpenCV can read' % (here, uri, path))
    grey = picture.astype(float) if picture.ndim == 2 else picture[:, :, :3].astype(float).mean(axis=2)
    if picture.dtype == np.uint16:
        grey /= 257.0
    solid = grey <= threshold
    block = max(1, int(math.isqrt(max(granularity, 1))))
    if block > 1:
        rows, cols = solid.shape
        padded = np.zeros((-(-rows // block) * block, -(-cols // block) * block), bool)
        padded[:rows, :cols] = solid
        coarse = padded.reshape(padded.shape[0] // block, block, padded.shape[1] // block, block).any(axis=(1, 3))
        solid = np.repeat(np.repeat(coarse, block, axis=0), block, axis=1)[:rows, :cols]
    x, y, yaw = planar(pose)
    z0 = float(pose[2, 3])
    return Shape('grid', x, y, yaw, cells=solid, resolution=scale, z_lo=z0, z_hi=z0 + height)
