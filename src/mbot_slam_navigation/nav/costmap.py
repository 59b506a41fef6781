"""costmap_2d's layered costmap, ROS-free: configuration from a costmap namespace and the layers.

Values are costmap_2d's (0 free, 1..252 inflated, 253 inscribed, 254 lethal, 255 unknown), in a
(rows = y, columns = x) uint8 array whose cell (0, 0) has its corner at ``origin`` [m] in the
costmap's ``global_frame``. The per-cell hot loops (ray tracing, inflation) are the C++ core's; this
module holds configuration and composition (numpy).

Both configuration styles are read:
- pre-Hydro (the tutorials): ``static_map``, the obstacle keys (``observation_sources``,
  ``obstacle_range``...) and the inflation keys at the top level of the costmap namespace;
- ``plugins: [{name: ..., type: costmap_2d::StaticLayer}, ...]`` with each layer's keys in
  ``<costmap>/<name>/`` (falling back to the top level, as ROS copies them there).
"""
import ast
import math
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from mbot_slam_navigation import _core
from mbot_slam_navigation.nav.params import ParamError, ParamReader, Warn, nearest_key

FREE, INSCRIBED, LETHAL, UNKNOWN = 0, 253, 254, 255

LAYER_TYPES = {
    'costmap_2d::StaticLayer': 'static',
    'costmap_2d::ObstacleLayer': 'obstacle',
    'costmap_2d::VoxelLayer': 'obstacle',  # a 2D obstacle layer here: the simulated lasers are planar
    'costmap_2d::InflationLayer': 'inflation',
}

# Keys of other nodes that tutorials put into costmap namespaces.
MOVE_BASE_KEYS = ('controller_frequency', 'planner_frequency', 'controller_patience', 'planner_patience',
                  'oscillation_timeout', 'oscillation_distance', 'max_planning_retries', 'recovery_behaviors',
                  'clearing_rotation_allowed', 'recovery_behavior_enabled', 'shutdown_costmaps',
                  'conservative_reset_dist', 'base_global_planner', 'base_local_planner')


def parse_footprint(value: Any, where: str) -> List[Tuple[float, float]]:
    """A footprint parameter: a list of [x, y] points, or the same written as a string."""
    if isinstance(value, str):
        try:
            value = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            raise ParamError('parameter %s: cannot read "%s" as a list of [x, y] points' % (where, value))
    try:
        points = [(float(p[0]), float(p[1])) for p in value]
        if any(len(p) != 2 for p in value):
            raise ValueError
    except (TypeError, ValueError, IndexError):
        raise ParamError('parameter %s: expected a list of [x, y] points, got %r' % (where, value))
    return points


class ObservationSource:
    """One ``observation_sources`` entry (LaserScan only)."""

    KEYS = ('topic', 'sensor_frame', 'observation_persistence', 'expected_update_rate', 'data_type',
            'clearing', 'marking', 'max_obstacle_height', 'min_obstacle_height', 'obstacle_range',
            'raytrace_range', 'inf_is_valid')

    def __init__(self, name: str, values: Dict[str, Any], layer: ParamReader, warn: Warn):
        r = ParamReader(values, '%s/%s' % (layer.ns, name), warn)
        self.name = name
        self.topic = r.string('topic', name)
        # Empty (the default): the frame of each scan's header.
        self.sensor_frame = r.frame('sensor_frame', '') if r.raw('sensor_frame', '') else ''
        self.observation_persistence = r.number('observation_persistence', 0.0, minimum=0.0)
        self.expected_update_rate = r.number('expected_update_rate', 0.0, minimum=0.0)
        self.data_type = r.string('data_type', 'PointCloud')
        if self.data_type != 'LaserScan':
            raise ParamError('parameter %s: data_type "%s" is not supported; only LaserScan sources are'
                             % (r.where('data_type'), self.data_type))
        self.clearing = r.boolean('clearing', False)
        self.marking = r.boolean('marking', True)
        self.max_obstacle_height = r.number('max_obstacle_height', layer.number('max_obstacle_height', 2.0))
        self.min_obstacle_height = r.number('min_obstacle_height', 0.0)
        self.obstacle_range = r.number('obstacle_range', layer.number('obstacle_range', 2.5), positive=True)
        self.raytrace_range = r.number('raytrace_range', layer.number('raytrace_range', 3.0), positive=True)
        # ROS defaults this to false, and then a laser's "no return" (+inf, REP 117) clears nothing,
        # so obstacles that moved away stay in the map forever; here +inf clears to the range.
        self.inf_is_valid = r.boolean('inf_is_valid', True)
        r.report_unknown()


class CostmapConfig:
    """Everything a costmap namespace configures. Raises ParamError naming the key on bad values."""

    def __init__(self, name: str, values: Optional[Dict[str, Any]], warn: Warn, ns_prefix: str = ''):
        values = dict(values or {})
        self.name = name
        ns = '%s/%s' % (ns_prefix.rstrip('/'), name)
        r = ParamReader(values, ns, warn)
        self.global_frame = r.frame('global_frame', 'map')
        self.robot_base_frame = r.frame('robot_base_frame', 'base_link')
        self.transform_tolerance = r.number('transform_tolerance', 0.3, minimum=0.0)
        self.update_frequency = r.number('update_frequency', 5.0, minimum=0.0)
        # ROS's default is 0 (never published); rviz users expect to see the costmap.
        self.publish_frequency = r.number('publish_frequency', 1.0, minimum=0.0)
        self.rolling_window = r.boolean('rolling_window', False)
        self.always_send_full_costmap = r.boolean('always_send_full_costmap', False)
        self.width = r.number('width', 10.0, positive=True)
        self.height = r.number('height', 10.0, positive=True)
        self.resolution = r.number('resolution', 0.05, positive=True)
        self.origin = (r.number('origin_x', 0.0), r.number('origin_y', 0.0))
        self.footprint_padding = r.number('footprint_padding', 0.01)
        if r.has('footprint') and r.values['footprint'] not in ('[]', [], None):
            footprint = parse_footprint(r.raw('footprint'), r.where('footprint'))
            if r.has('robot_radius'):
                r.read_keys.add('robot_radius')
                warn('%s: both footprint and robot_radius are set; the footprint polygon is used' % ns)
        else:
            r.read_keys.add('footprint')
            radius = r.number('robot_radius', 0.46, positive=True)
            footprint = [tuple(p) for p in _core._circle_footprint(radius)]
        points = [np.array(p, float) for p in footprint]
        try:
            _core._validate_footprint(points)
        except ValueError as e:
            raise ParamError('parameter %s: %s' % (r.where('footprint'), e))
        padded = _core._pad_footprint(points, self.footprint_padding)
        self.footprint = [tuple(p) for p in padded]
        self.inscribed_radius = _core._inscribed_radius(padded)
        self.circumscribed_radius = _core._circumscribed_radius(padded)

        self.layers = []  # (name, kind, ParamReader of the layer's own keys + top-level fallbacks)
        sub_namespaces = set()
        if r.has('plugins'):
            plugins = r.raw('plugins')
            if not isinstance(plugins, list):
                raise ParamError('parameter %s must be a list of {name, type}, got %r' % (r.where('plugins'), plugins))
            for i, plugin in enumerate(plugins):
                if not isinstance(plugin, dict) or 'name' not in plugin or 'type' not in plugin:
                    raise ParamError('parameter %s[%d] must have a name and a type, got %r' % (r.where('plugins'), i, plugin))
                kind = LAYER_TYPES.get(plugin['type'])
                if kind is None:
                    guess = nearest_key(plugin['type'], LAYER_TYPES)
                    raise ParamError('parameter %s[%d]: unknown layer type "%s"%s; known: %s' % (
                        r.where('plugins'), i, plugin['type'], ' (did you mean %s?)' % guess if guess else '',
                        ', '.join(sorted(LAYER_TYPES))))
                layer_values = values.get(plugin['name'], {})
                if not isinstance(layer_values, dict):
                    layer_values = {}
                sub_namespaces.add(plugin['name'])
                self.layers.append((plugin['name'], kind, ParamReader(layer_values, '%s/%s' % (ns, plugin['name']), warn)))
        else:
            # Pre-Hydro: the layers ROS builds from the old keys, which live at the top level.
            if r.boolean('static_map', True):
                self.layers.append(('static_layer', 'static', r))
            map_type = r.string('map_type', 'costmap')
            if map_type not in ('costmap', 'voxel'):
                raise ParamError('parameter %s must be costmap or voxel, got "%s"' % (r.where('map_type'), map_type))
            self.layers.append(('obstacle_layer', 'obstacle', r))
            self.layers.append(('inflation_layer', 'inflation', r))

        self.static = None
        self.obstacle = None
        self.inflation = None
        for layer_name, kind, lr in self.layers:
            if kind == 'static':
                self.static = self._static_params(lr, r)
                self.static['name'] = layer_name
            elif kind == 'obstacle':
                self.obstacle = self._obstacle_params(lr, r, warn)
                self.obstacle['name'] = layer_name
                sub_namespaces.update(self.obstacle['sources'])
            else:
                self.inflation = self._inflation_params(lr, r)
                self.inflation['name'] = layer_name
            if lr is not r:
                lr.report_unknown(skip=self.obstacle['sources'] if kind == 'obstacle' else ())
        # Voxel-layer keys are accepted (the layer is 2D here) but not reported as unknown.
        for key in ('origin_z', 'z_resolution', 'z_voxels', 'unknown_threshold', 'mark_threshold', 'publish_voxel_map'):
            r.read_keys.add(key)
        r.report_unknown(skip=sub_namespaces, elsewhere={k: 'move_base' for k in MOVE_BASE_KEYS})

    @staticmethod
    def _fallback(lr: ParamReader, top: ParamReader, kind: str, key: str, default: Any, **kw) -> Any:
        if lr is not top and not lr.has(key) and top.has(key):
            return getattr(top, kind)(key, default, **kw)
        return getattr(lr, kind)(key, default, **kw)

    def _static_params(self, lr: ParamReader, top: ParamReader) -> Dict[str, Any]:
        f = self._fallback
        return {
            'map_topic': f(lr, top, 'string', 'map_topic', 'map'),
            'first_map_only': f(lr, top, 'boolean', 'first_map_only', False),
            'subscribe_to_updates': f(lr, top, 'boolean', 'subscribe_to_updates', False),
            'track_unknown_space': f(lr, top, 'boolean', 'track_unknown_space', True),
            'use_maximum': f(lr, top, 'boolean', 'use_maximum', False),
            'lethal_cost_threshold': f(lr, top, 'integer', 'lethal_cost_threshold', 100, minimum=0),
            'unknown_cost_value': f(lr, top, 'integer', 'unknown_cost_value', -1),
            'trinary_costmap': f(lr, top, 'boolean', 'trinary_costmap', True),
            'enabled': f(lr, top, 'boolean', 'enabled', True),
        }

    def _obstacle_params(self, lr: ParamReader, top: ParamReader, warn: Warn) -> Dict[str, Any]:
        f = self._fallback
        names = f(lr, top, 'string', 'observation_sources', '')
        # The layer's range keys are the defaults of its sources.
        for key in ('obstacle_range', 'raytrace_range', 'max_obstacle_height'):
            if lr is not top and not lr.has(key) and top.has(key):
                lr.values[key] = top.values[key]
        sources = {}
        for source_name in names.split():
            container = lr if source_name in lr.values else top
            values = container.values.get(source_name)
            if not isinstance(values, dict):
                raise ParamError('observation source "%s" is listed in %s but %s is not a dict of its parameters'
                                 % (source_name, lr.where('observation_sources'), container.where(source_name)))
            sources[source_name] = ObservationSource(source_name, values, lr, warn)
        return {
            'sources': sources,
            'track_unknown_space': f(lr, top, 'boolean', 'track_unknown_space', False),
            'footprint_clearing_enabled': f(lr, top, 'boolean', 'footprint_clearing_enabled', True),
            'combination_method': f(lr, top, 'integer', 'combination_method', 1),
            'enabled': f(lr, top, 'boolean', 'enabled', True),
        }

    def _inflation_params(self, lr: ParamReader, top: ParamReader) -> Dict[str, Any]:
        f = self._fallback
        return {
            'inflation_radius': f(lr, top, 'number', 'inflation_radius', 0.55, minimum=0.0),
            'cost_scaling_factor': f(lr, top, 'number', 'cost_scaling_factor', 10.0, minimum=0.0),
            'inflate_unknown': f(lr, top, 'boolean', 'inflate_unknown', False),
            'enabled': f(lr, top, 'boolean', 'enabled', True),
        }


def static_costs(data: np.ndarray, params: Dict[str, Any]) -> np.ndarray:
    """costmap_2d's StaticLayer::interpretValue over an OccupancyGrid's data (int8, rows = y)."""
    data = data.astype(np.int16)
    unknown = data == params['unknown_cost_value'] if params['unknown_cost_value'] >= 0 else data < 0
    out = np.zeros(data.shape, np.uint8)
    if params['trinary_costmap']:
        out[data >= params['lethal_cost_threshold']] = LETHAL
    else:
        scaled = np.clip(data, 0, 100).astype(np.float64) / params['lethal_cost_threshold'] * LETHAL
        out[:] = np.minimum(scaled, LETHAL).astype(np.uint8)
        out[data >= params['lethal_cost_threshold']] = LETHAL
    out[unknown] = UNKNOWN if params['track_unknown_space'] else FREE
    return out


def combine_max(master: np.ndarray, layer: np.ndarray) -> None:
    """costmap_2d's updateWithMax: a layer's known cells raise the master (unknown master cells take them)."""
    known = layer != UNKNOWN
    take = known & ((master == UNKNOWN) | (layer > master))
    master[take] = layer[take]


def shift_into(src: np.ndarray, src_origin: Tuple[float, float], dst_shape: Tuple[int, int],
               dst_origin: Tuple[float, float], resolution: float, fill: int) -> np.ndarray:
    """The values of ``src`` re-placed on a grid of the same resolution with another origin/size."""
    out = np.full(dst_shape, fill, np.uint8)
    dx = int(round((src_origin[0] - dst_origin[0]) / resolution))
    dy = int(round((src_origin[1] - dst_origin[1]) / resolution))
    h, w = src.shape
    x0, y0 = max(dx, 0), max(dy, 0)
    x1, y1 = min(dx + w, dst_shape[1]), min(dy + h, dst_shape[0])
    if x1 > x0 and y1 > y0:
        out[y0:y1, x0:x1] = src[y0 - dy:y1 - dy, x0 - dx:x1 - dx]
    return out


def sample_into(src: np.ndarray, src_origin: Tuple[float, float], src_resolution: float, dst_shape: Tuple[int, int],
                dst_origin: Tuple[float, float], dst_resolution: float, fill: int) -> np.ndarray:
    """Nearest-cell resampling of ``src`` onto another grid (a static map into a rolling window)."""
    h, w = dst_shape
    xs = dst_origin[0] + (np.arange(w) + 0.5) * dst_resolution
    ys = dst_origin[1] + (np.arange(h) + 0.5) * dst_resolution
    cx = np.floor((xs - src_origin[0]) / src_resolution).astype(np.int64)
    cy = np.floor((ys - src_origin[1]) / src_resolution).astype(np.int64)
    out = np.full(dst_shape, fill, np.uint8)
    vx = (cx >= 0) & (cx < src.shape[1])
    vy = (cy >= 0) & (cy < src.shape[0])
    if vx.any() and vy.any():
        out[np.ix_(vy, vx)] = src[np.ix_(cy[vy], cx[vx])]
    return out


class LayeredCostmap:
    """The master costmap and its layers for one CostmapConfig.

    The static layer takes maps (``set_map``), the obstacle layer scans with their sensor poses
    (``add_scan``); ``update(robot_pose)`` moves a rolling window, applies the observations and
    composes static -> obstacle -> inflation into ``costs`` (and ``core``, a C++ _Costmap of it).
    """

    def __init__(self, config: CostmapConfig, warn: Warn):
        self.config = config
        self.warn = warn
        self.resolution = config.resolution
        self.static_map = None  # (costs, origin, resolution) of the last map
        self.map_generation = 0
        self.map_received = False
        ob = config.obstacle
        self.obstacle_default = UNKNOWN if ob and ob['track_unknown_space'] else FREE
        self.default_value = UNKNOWN if (config.static and config.static['track_unknown_space']) or (
            ob and ob['track_unknown_space']) else FREE
        if config.rolling_window or config.static is None:
            w = max(1, int(round(config.width / config.resolution)))
            h = max(1, int(round(config.height / config.resolution)))
            self._resize((h, w), config.origin, config.resolution)
        else:
            self._resize((1, 1), config.origin, config.resolution)  # sized by the first map
        self.costs = np.full(self.shape, self.default_value, np.uint8)
        self.core = _core._Costmap(self.costs, self.resolution, np.array(self.origin, float))
        self.observations = {name: [] for name in (ob['sources'] if ob else {})}
        self.height_warned = set()

    @property
    def ready(self) -> bool:
        """False while a static layer waits for its first map."""
        return self.config.static is None or self.map_received

    def _resize(self, shape, origin, resolution):
        self.shape = shape
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = resolution
        self.obstacle_layer = _core._Costmap(np.full(shape, self.obstacle_default if self.config.obstacle else FREE, np.uint8),
                                             resolution, np.array(self.origin))

    def set_map(self, data: np.ndarray, origin: Tuple[float, float], resolution: float) -> None:
        """A new map for the static layer (OccupancyGrid data, rows = y, origin of cell (0, 0) [m])."""
        if self.config.static is None:
            return
        if self.config.static['first_map_only'] and self.map_received:
            return
        costs = static_costs(data, self.config.static)
        self.static_map = (costs, (float(origin[0]), float(origin[1])), float(resolution))
        self.map_received = True
        self.map_generation += 1
        if not self.config.rolling_window:
            # The master follows the map's geometry (SLAM grows it); obstacles keep their places.
            if costs.shape != self.shape or abs(resolution - self.resolution) > 1e-9 or \
                    max(abs(origin[0] - self.origin[0]), abs(origin[1] - self.origin[1])) > 1e-9:
                old = self.obstacle_layer.costs()
                old_origin, old_res = self.origin, self.resolution
                self._resize(costs.shape, origin, resolution)
                if abs(old_res - resolution) < 1e-9:
                    self.obstacle_layer.set_costs(shift_into(old, old_origin, costs.shape, self.origin, resolution,
                                                             self.obstacle_default))

    def add_scan(self, source: str, stamp: float, sensor_pose: Tuple[float, float, float], sensor_height: float,
                 angle_min: float, angle_increment: float, range_min: float, range_max: float, ranges) -> bool:
        """Buffers one scan of ``source`` (sensor pose in the global frame, height [m] above it).

        Returns False (and warns once per source) when the sensor's height is outside the source's
        [min_obstacle_height, max_obstacle_height]: costmap_2d drops every point of such a scan.
        """
        src = self.config.obstacle['sources'][source]
        if not src.min_obstacle_height <= sensor_height <= src.max_obstacle_height:
            if source not in self.height_warned:
                self.height_warned.add(source)
                self.warn('observation source %s: the sensor is %.3f m high, outside [min_obstacle_height %.3f, '
                          'max_obstacle_height %.3f], so none of its points mark or clear anything'
                          % (source, sensor_height, src.min_obstacle_height, src.max_obstacle_height))
            return False
        obs = (stamp, tuple(sensor_pose), angle_min, angle_increment, range_min, range_max,
               np.asarray(ranges, np.float32))
        buf = self.observations[source]
        if src.observation_persistence == 0.0:
            buf[:] = [obs]
        else:
            buf.append(obs)
            while buf and stamp - buf[0][0] > src.observation_persistence:
                buf.pop(0)
        return True

    def stale_sources(self, now: float) -> List[str]:
        """Sources whose expected_update_rate is overdue (costmap_2d's isCurrent is false)."""
        stale = []
        if self.config.obstacle:
            for name, src in self.config.obstacle['sources'].items():
                if src.expected_update_rate > 0:
                    buf = self.observations[name]
                    last = buf[-1][0] if buf else None
                    if last is None or now - last > src.expected_update_rate:
                        stale.append(name)
        return stale

    def update(self, robot_pose: Tuple[float, float, float]) -> np.ndarray:
        """One update cycle at ``robot_pose`` (global frame); returns the master costs."""
        c = self.config
        if c.rolling_window:
            h, w = self.shape
            new_origin = (robot_pose[0] - w * self.resolution / 2.0, robot_pose[1] - h * self.resolution / 2.0)
            self.obstacle_layer.move_origin(np.array(new_origin), self.obstacle_default)
            self.origin = tuple(self.obstacle_layer.origin)
        master = np.full(self.shape, self.default_value, np.uint8)
        if c.static and c.static['enabled'] and self.static_map is not None:
            costs, origin, res = self.static_map
            if c.rolling_window:
                master = sample_into(costs, origin, res, self.shape, self.origin, self.resolution, self.default_value)
            else:
                master = costs.copy()
        if c.obstacle and c.obstacle['enabled']:
            for name, src in c.obstacle['sources'].items():
                for (_, pose, amin, ainc, rmin, rmax, ranges) in self.observations[name]:
                    # Clearing and marking in one pass per scan, as ObstacleLayer does per cloud.
                    self.obstacle_layer.update_with_scan(np.array(pose, float), amin, ainc, rmin, rmax, ranges,
                                                         src.obstacle_range, src.raytrace_range, src.marking,
                                                         src.clearing, src.inf_is_valid)
            layer = self.obstacle_layer.costs()
            if c.obstacle['footprint_clearing_enabled']:
                for (x, y) in self.obstacle_layer.footprint_cells(np.array(robot_pose, float), self._footprint_np()):
                    layer[y, x] = FREE
                self.obstacle_layer.set_costs(layer)
            if c.obstacle['combination_method'] == 0:
                known = layer != UNKNOWN
                master[known] = layer[known]
            else:
                combine_max(master, layer)
        if c.inflation and c.inflation['enabled']:
            _core._inflate(master, self.resolution, c.inscribed_radius, c.inflation['inflation_radius'],
                           c.inflation['cost_scaling_factor'], c.inflation['inflate_unknown'])
        self.costs = master
        self.core = _core._Costmap(master, self.resolution, np.array(self.origin, float))
        return master

    def _footprint_np(self):
        return [np.array(p, float) for p in self.config.footprint]

    def reset_obstacles(self, keep_window: Optional[Tuple[float, float, float]] = None) -> None:
        """Clears the obstacle layer (clear_costmaps), or only outside a square of side ``keep_window[2]``
        centred on (keep_window[0], keep_window[1]) (ClearCostmapRecovery's reset_distance)."""
        layer = self.obstacle_layer.costs()
        if keep_window is None:
            layer[:] = self.obstacle_default
        else:
            x, y, side = keep_window
            keep = np.zeros(layer.shape, bool)
            x0 = int(math.floor((x - side / 2.0 - self.origin[0]) / self.resolution))
            y0 = int(math.floor((y - side / 2.0 - self.origin[1]) / self.resolution))
            x1 = int(math.ceil((x + side / 2.0 - self.origin[0]) / self.resolution))
            y1 = int(math.ceil((y + side / 2.0 - self.origin[1]) / self.resolution))
            keep[max(y0, 0):max(y1, 0), max(x0, 0):max(x1, 0)] = True
            layer[~keep] = self.obstacle_default
        self.obstacle_layer.set_costs(layer)

    def world_to_cell(self, x: float, y: float) -> Tuple[int, int]:
        return (int(math.floor((x - self.origin[0]) / self.resolution)),
                int(math.floor((y - self.origin[1]) / self.resolution)))
