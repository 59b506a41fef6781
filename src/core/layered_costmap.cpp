#include "mbot_slam_navigation/core/layered_costmap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "mbot_slam_navigation/core/local_planner.h"
#include "mbot_slam_navigation/core/obstacle_layer.h"

namespace mbot {
namespace core {
namespace {

const std::map<std::string, std::string> kLayerTypes = {
    {"costmap_2d::StaticLayer", "static"},
    {"costmap_2d::ObstacleLayer", "obstacle"},
    {"costmap_2d::VoxelLayer", "obstacle"},  // a 2D obstacle layer here: the simulated lasers are planar
    {"costmap_2d::InflationLayer", "inflation"},
    {"nav2_costmap_2d::KeepoutFilter", "keepout"},
    {"nav2_costmap_2d::SpeedFilter", "speed"},
    {"costmap_prohibition_layer_namespace::CostmapProhibitionLayer", "keepout"},
};
const char* const kProhibitionType = "costmap_prohibition_layer_namespace::CostmapProhibitionLayer";

// Keys of move_base that tutorials put into costmap namespaces.
const std::vector<std::string> kMoveBaseKeys = {
    "controller_frequency", "planner_frequency", "controller_patience", "planner_patience", "oscillation_timeout",
    "oscillation_distance", "max_planning_retries", "recovery_behaviors", "clearing_rotation_allowed",
    "recovery_behavior_enabled", "shutdown_costmaps", "conservative_reset_dist", "base_global_planner",
    "base_local_planner"};

std::vector<std::string> keysOf(const std::map<std::string, std::string>& m) {
  std::vector<std::string> out;
  for (const auto& [k, _] : m) out.push_back(k);
  return out;
}

const char* const kFootprintDoc = "[m] the robot's outline as [[x, y], ...] in the base frame (or robot_radius)";
const char* const kRadiusDoc = "[m] radius of a round robot, used when footprint is not set";
const char* const kPluginsDoc = "the layers in order, [{name: ..., type: costmap_2d::StaticLayer}, ...] "
                                "(Static, Obstacle, Voxel as 2D, Inflation); without it, the pre-Hydro keys";
const char* const kEnabledDoc = "the layer is used";
constexpr double kDefaultRobotRadius = 0.46;  // [m] costmap_2d's

// A layer's key, read from its own namespace or, when only set there, the costmap's top level.
template <class F>
auto fallback(ParamReader& layer, ParamReader& top, const std::string& key, F read) {
  if (&layer != &top && !layer.has(key) && top.has(key)) return read(top);
  return read(layer);
}

ObservationSourceConfig readSource(const std::string& name, const ParamValue& values, ParamReader& layer, const Warn& warn) {
  ParamReader r(values, layer.ns() + "/" + name, warn);
  ObservationSourceConfig s;
  s.name = name;
  s.topic = r.string("topic", name, "the sensor's topic (default: the source's name)");
  const char* frame_doc = "frame of the sensor ('': each message's header frame)";
  const ParamValue sf = r.raw("sensor_frame", ParamValue::ofString(""), frame_doc, "frame");
  s.sensor_frame = sf.type == ParamValue::Type::kString && sf.s.empty() ? "" : r.frame("sensor_frame", "", frame_doc);
  s.observation_persistence = r.number("observation_persistence", s.observation_persistence,
                                       "[s] how long a reading is kept (0: the latest only)", 0.0);
  s.expected_update_rate = r.number("expected_update_rate", kUnsetExpectedUpdateRate,
                                    "[s] longest gap between readings before the sensor counts as stale and the robot "
                                    "stops (0: never; costmap_2d's default 0)",
                                    0.0);
  const std::string data_type = r.string("data_type", "PointCloud", "message type: only LaserScan is supported here");
  if (data_type != "LaserScan") {
    throw ParamError("parameter " + r.where("data_type") + ": data_type \"" + data_type +
                     "\" is not supported; only LaserScan sources are");
  }
  s.clearing = r.boolean("clearing", s.clearing, "clear the cells along each beam");
  s.marking = r.boolean("marking", s.marking, "mark the cell where each beam ends");
  s.max_obstacle_height =
      r.number("max_obstacle_height",
               layer.number("max_obstacle_height", s.max_obstacle_height, "[m] highest reading that counts (layer default)"),
               "[m] highest reading that counts");
  s.min_obstacle_height = r.number("min_obstacle_height", s.min_obstacle_height, "[m] lowest reading that counts");
  s.obstacle_range = r.number("obstacle_range",
                              layer.number("obstacle_range", s.obstacle_range, "[m] farthest reading that marks (layer default)",
                                           std::nullopt, true),
                              "[m] farthest reading that marks an obstacle", std::nullopt, true);
  s.raytrace_range = r.number("raytrace_range",
                              layer.number("raytrace_range", s.raytrace_range, "[m] farthest beam that clears (layer default)",
                                           std::nullopt, true),
                              "[m] farthest a beam clears free space", std::nullopt, true);
  s.raytrace_end_margin = r.number("raytrace_end_margin", s.raytrace_end_margin,
                                   "[m] a return's beam clears only the cells it leaves more than this short of the return, so "
                                   "that the laser's noise does not erase the cell in front of a surface (ours; 0: costmap_2d's "
                                   "rule)",
                                   0.0);
  s.inf_is_valid = r.boolean("inf_is_valid", s.inf_is_valid,
                             "an infinite range clears the beam's whole length (ROS's default false: it clears nothing)");
  s.too_close_is_obstacle = r.boolean("too_close_is_obstacle", s.too_close_is_obstacle,
                                      "a -inf range (nearer than range_min) marks an obstacle at range_min");
  r.reportUnknown();
  return s;
}

/// A parameter that must be a list (`what` says of what, for the error).
ParamValue readList(ParamReader& r, const std::string& key, const char* doc, const std::string& what) {
  const ParamValue v = r.raw(key, ParamValue::ofList(), doc, "list");
  if (v.type != ParamValue::Type::kList) {
    throw ParamError("parameter " + r.where(key) + " must be a list of " + what + ", got " + v.repr());
  }
  return v;
}

ZonePolygon readPolygon(const ParamValue& item, const std::string& where) {
  ZonePolygon z;
  z.name = where;
  ParamValue points = item;
  if (item.type == ParamValue::Type::kMap) {
    const ParamValue* name = item.get("name");
    const ParamValue* pts = item.get("points");
    if (!pts) throw ParamError("parameter " + where + " must be [[x, y], ...] or {name: ..., points: [[x, y], ...]}");
    if (name && name->type == ParamValue::Type::kString && !name->s.empty()) z.name = "'" + name->s + "'";
    points = *pts;
  }
  for (const auto& p : parseFootprint(points, where)) z.points.push_back(p);
  if (z.points.size() < 3) {
    throw ParamError("parameter " + where + ": a zone's polygon needs at least 3 points, it has " +
                     std::to_string(z.points.size()));
  }
  return z;
}

/// One filter's keys; a problem goes into the config's `error` (the costmap runs without it).
FilterConfig readFilter(const std::string& name, const std::string& type, const std::string& kind, ParamReader& lr) {
  FilterConfig f;
  f.name = name;
  f.type = type;
  f.kind = kind == "speed" ? FilterConfig::Kind::kSpeed : FilterConfig::Kind::kKeepout;
  f.enabled = lr.boolean("enabled", true, kEnabledDoc);
  lr.ignored("filter_info_topic",
             "Nav2's CostmapFilterInfo is not read: the filter takes its mask from mask_topic (and base, multiplier)");
  lr.ignored("transform_tolerance", "masks must be in the costmap's global_frame");
  try {
    const bool speed = f.kind == FilterConfig::Kind::kSpeed;
    if (!speed) {
      const ParamValue areas = readList(lr, "prohibition_areas",
                                        "keep-out filter: zones as polygons in global_frame, [[[x, y], ...], ...] "
                                        "(costmap_prohibition_layer's), or [{name: ..., points: [[x, y], ...]}, ...]",
                                        "polygons");
      for (std::size_t i = 0; i < areas.items.size(); ++i) {
        f.zones.push_back(readPolygon(areas.items[i], lr.where("prohibition_areas") + "[" + std::to_string(i) + "]"));
      }
    }
    const bool prohibition = type == kProhibitionType;
    const std::string topic_default = prohibition || !f.zones.empty() ? ""
                                      : speed                          ? "speed_filter_mask"
                                                                       : "keepout_filter_mask";
    f.mask_topic = lr.string("mask_topic", topic_default,
                             "filters: the mask's nav_msgs/OccupancyGrid topic, as map_server serves a mask image "
                             "(Nav2's default names: keepout_filter_mask, speed_filter_mask; '': polygons only)");
    if (!f.mask_topic.empty() && !f.zones.empty()) {
      throw ParamError("parameters " + lr.where("mask_topic") + " and " + lr.where("prohibition_areas") +
                       ": give the zones one way, a mask or polygons");
    }
    if (f.mask_topic.empty() && f.zones.empty()) {
      throw ParamError(speed ? "parameter " + lr.where("mask_topic") + " is empty: a speed filter needs a mask"
                             : "parameter " + lr.where("prohibition_areas") + ": no zones (and no mask_topic)");
    }
    if (speed) {
      f.base = lr.number("base", f.base, "speed filter: limit = base + multiplier * mask value (Nav2's filter info)");
      f.multiplier = lr.number("multiplier", f.multiplier, "speed filter: limit = base + multiplier * mask value");
      f.percent = lr.boolean("speed_limit_in_percent", f.percent,
                             "speed filter: the limit is a percentage of max_vel_x (false: [m/s])");
    }
  } catch (const ParamError& e) {
    f.error = e.what();
  }
  return f;
}

}  // namespace

Footprint parseFootprint(const ParamValue& value, const std::string& where) {
  ParamValue v = value;
  if (v.type == ParamValue::Type::kString) {
    // "[[x, y], [x, y], ...]": numbers in brackets, pairwise.
    std::vector<double> numbers;
    std::string text = v.s;
    int depth = 0, max_depth = 0;
    for (char& c : text) {
      if (c == '[') max_depth = std::max(max_depth, ++depth);
      if (c == ']') --depth;
      if (c == '[' || c == ']' || c == ',') c = ' ';
    }
    std::istringstream in(text);
    double x;
    while (in >> x) numbers.push_back(x);
    if (!in.eof() || depth != 0 || max_depth != 2 || numbers.size() % 2 != 0 || numbers.empty()) {
      throw ParamError("parameter " + where + ": cannot read \"" + value.s + "\" as a list of [x, y] points");
    }
    Footprint out;
    for (std::size_t k = 0; k < numbers.size(); k += 2) out.emplace_back(numbers[k], numbers[k + 1]);
    return out;
  }
  Footprint out;
  bool ok = v.type == ParamValue::Type::kList;
  for (const auto& p : v.items) {
    if (p.type != ParamValue::Type::kList || p.items.size() != 2 || !p.items[0].isNumber() || !p.items[1].isNumber()) {
      ok = false;
      break;
    }
    out.emplace_back(p.items[0].number(), p.items[1].number());
  }
  if (!ok) throw ParamError("parameter " + where + ": expected a list of [x, y] points, got " + value.repr());
  return out;
}

CostmapConfig readCostmapConfig(const std::string& name, const ParamValue& values, const Warn& warn_or_empty,
                                const std::string& ns_prefix) {
  const Warn warn = orIgnore(warn_or_empty);
  CostmapConfig c;
  c.name = name;
  std::string prefix = ns_prefix;
  while (!prefix.empty() && prefix.back() == '/') prefix.pop_back();
  const std::string ns = prefix + "/" + name;
  ParamReader r(values, ns, warn);
  c.global_frame = r.frame("global_frame", c.global_frame, "frame the costmap lies in");
  c.robot_base_frame = r.frame("robot_base_frame", c.robot_base_frame, "the robot's base frame");
  c.transform_tolerance = r.number("transform_tolerance", c.transform_tolerance,
                                   "[s] how old the robot's pose may be before the costmap stops updating", 0.0);
  c.update_frequency = r.number("update_frequency", c.update_frequency, "[Hz] how often the layers are updated", 0.0);
  c.publish_frequency = r.number("publish_frequency", c.publish_frequency,
                                 "[Hz] how often the costmap is published (ROS's default 0: never)", 0.0);
  c.rolling_window = r.boolean("rolling_window", c.rolling_window, "the costmap moves with the robot, centred on it");
  c.always_send_full_costmap = r.boolean("always_send_full_costmap", c.always_send_full_costmap,
                                         "publish the whole costmap every time instead of costmap_updates");
  c.width = r.number("width", c.width, "[m] size along x (rolling window, or no static map)", std::nullopt, true);
  c.height = r.number("height", c.height, "[m] size along y (rolling window, or no static map)", std::nullopt, true);
  c.resolution = r.number("resolution", c.resolution, "[m/cell] cell size", std::nullopt, true);
  c.origin_x = r.number("origin_x", c.origin_x, "[m] x of the lower-left corner (without a static map)");
  c.origin_y = r.number("origin_y", c.origin_y, "[m] y of the lower-left corner (without a static map)");
  c.footprint_padding = r.number("footprint_padding", c.footprint_padding, "[m] added around the footprint");
  Footprint footprint;
  const ParamValue* fp = r.values().get("footprint");
  const bool fp_empty = !fp || fp->type == ParamValue::Type::kNone || (fp->type == ParamValue::Type::kList && fp->items.empty()) ||
                        (fp->type == ParamValue::Type::kString && (fp->s == "[]" || fp->s.empty()));
  if (!fp_empty) {
    footprint = parseFootprint(r.raw("footprint", ParamValue::ofList(), kFootprintDoc, "list"), r.where("footprint"));
    if (r.has("robot_radius")) {
      r.number("robot_radius", kDefaultRobotRadius, kRadiusDoc);
      warn(ns + ": both footprint and robot_radius are set; the footprint polygon is used");
    }
  } else {
    r.raw("footprint", ParamValue::ofList(), kFootprintDoc, "list");
    footprint = circleFootprint(r.number("robot_radius", kDefaultRobotRadius, kRadiusDoc, std::nullopt, true));
  }
  try {
    validateFootprint(footprint);
  } catch (const std::invalid_argument& e) {
    throw ParamError("parameter " + r.where("footprint") + ": " + e.what());
  }
  c.footprint = padFootprint(footprint, c.footprint_padding);
  c.inscribed_radius = inscribedRadius(c.footprint);
  c.circumscribed_radius = circumscribedRadius(c.footprint);

  // Layers: (name, kind, reader of the layer's keys; the top-level reader for the pre-Hydro style).
  std::vector<std::tuple<std::string, std::string, std::unique_ptr<ParamReader>, std::string>> layers;
  std::set<std::string> sub_namespaces;
  // A plugin's or filter's own reader, over its namespace <ns>/<name> (empty when not set).
  auto layerReader = [&](const std::string& lname) {
    const ParamValue* lv = r.values().get(lname);
    sub_namespaces.insert(lname);
    return std::make_unique<ParamReader>(lv && lv->type == ParamValue::Type::kMap ? *lv : ParamValue::ofMap(),
                                         ns + "/" + lname, warn);
  };
  if (r.has("plugins")) {
    const ParamValue plugins = readList(r, "plugins", kPluginsDoc, "{name, type}");
    for (std::size_t i = 0; i < plugins.items.size(); ++i) {
      const ParamValue& p = plugins.items[i];
      const ParamValue* pname = p.get("name");
      const ParamValue* ptype = p.get("type");
      const std::string at = "parameter " + r.where("plugins") + "[" + std::to_string(i) + "]";
      if (!pname || !ptype || pname->type != ParamValue::Type::kString || ptype->type != ParamValue::Type::kString) {
        throw ParamError(at + " must have a name and a type, got " + p.repr());
      }
      const auto kind = kLayerTypes.find(ptype->s);
      if (kind == kLayerTypes.end()) {
        const std::string guess = nearestKey(ptype->s, keysOf(kLayerTypes));
        std::string known;
        for (const auto& [k, _] : kLayerTypes) known += (known.empty() ? "" : ", ") + k;
        throw ParamError(at + ": unknown layer type \"" + ptype->s + "\"" + (guess.empty() ? "" : " (did you mean " + guess + "?)") +
                         "; known: " + known);
      }
      layers.emplace_back(pname->s, kind->second, layerReader(pname->s), ptype->s);
    }
  } else {
    // Pre-Hydro: the layers ROS builds from the old keys, which live at the top level.
    r.raw("plugins", ParamValue::ofList(), kPluginsDoc, "list");
    if (r.boolean("static_map", true, "without plugins: build a static layer from the map topic")) {
      layers.emplace_back("static_layer", "static", nullptr, "costmap_2d::StaticLayer");
    }
    const std::string map_type = r.string("map_type", "costmap", "without plugins: costmap or voxel (both 2D here)");
    if (map_type != "costmap" && map_type != "voxel") {
      throw ParamError("parameter " + r.where("map_type") + " must be costmap or voxel, got \"" + map_type + "\"");
    }
    layers.emplace_back("obstacle_layer", "obstacle", nullptr, "costmap_2d::ObstacleLayer");
    layers.emplace_back("inflation_layer", "inflation", nullptr, "costmap_2d::InflationLayer");
  }
  // Nav2's filters list: [{name: ..., type: ...}] or [name, ...] with <name>/plugin.
  const ParamValue filters = readList(r, "filters",
                                     "costmap filters, [{name: ..., type: nav2_costmap_2d::KeepoutFilter}, ...] "
                                     "(KeepoutFilter, SpeedFilter, CostmapProhibitionLayer); with either style",
                                     "{name, type}");
  for (std::size_t i = 0; i < filters.items.size(); ++i) {
    const ParamValue& p = filters.items[i];
    const std::string at = "parameter " + r.where("filters") + "[" + std::to_string(i) + "]";
    std::string fname, ftype;
    if (p.type == ParamValue::Type::kString) {
      fname = p.s;
      const ParamValue* sub = r.values().get(fname);
      const ParamValue* t = sub ? sub->get("plugin") : nullptr;
      if (!t) t = sub ? sub->get("type") : nullptr;
      if (t && t->type == ParamValue::Type::kString) ftype = t->s;
    } else if (const ParamValue *pn = p.get("name"), *pt = p.get("type"); pn && pt && pn->type == ParamValue::Type::kString &&
                                                                          pt->type == ParamValue::Type::kString) {
      fname = pn->s;
      ftype = pt->s;
    }
    if (fname.empty() || ftype.empty()) {
      throw ParamError(at + " must be {name: ..., type: ...} (or a name with <name>/plugin set), got " + p.repr());
    }
    const auto kind = kLayerTypes.find(ftype);
    if (kind == kLayerTypes.end() || (kind->second != "keepout" && kind->second != "speed")) {
      throw ParamError(at + ": \"" + ftype + "\" is not a filter; known: nav2_costmap_2d::KeepoutFilter, "
                       "nav2_costmap_2d::SpeedFilter, " + kProhibitionType);
    }
    layers.emplace_back(fname, kind->second, layerReader(fname), ftype);
  }
  for (auto& [layer_name, kind, reader, type] : layers) {
    ParamReader& lr = reader ? *reader : r;
    c.layers.emplace_back(layer_name, kind);
    std::set<std::string> skip;
    if (kind == "static") {
      StaticLayerConfig s;
      const StaticLayerConfig d;
      s.name = layer_name;
      s.map_topic = fallback(lr, r, "map_topic", [&](ParamReader& p) {
        return p.string("map_topic", d.map_topic, "static layer: the map's topic");
      });
      s.first_map_only = fallback(lr, r, "first_map_only", [&](ParamReader& p) {
        return p.boolean("first_map_only", d.first_map_only, "static layer: keep the first map, ignore later ones");
      });
      s.subscribe_to_updates = fallback(lr, r, "subscribe_to_updates", [&](ParamReader& p) {
        return p.boolean("subscribe_to_updates", d.subscribe_to_updates, "static layer: also read <map_topic>_updates");
      });
      s.track_unknown_space = fallback(lr, r, "track_unknown_space", [&](ParamReader& p) {
        return p.boolean("track_unknown_space", d.track_unknown_space,
                         "static layer: unknown map cells stay unknown (else free); obstacle layer: cells start unknown");
      });
      s.use_maximum = fallback(lr, r, "use_maximum", [&](ParamReader& p) {
        return p.boolean("use_maximum", d.use_maximum, "static layer: combine by maximum instead of overwriting");
      });
      s.lethal_cost_threshold = static_cast<int>(fallback(lr, r, "lethal_cost_threshold", [&](ParamReader& p) {
        return p.integer("lethal_cost_threshold", d.lethal_cost_threshold,
                         "static layer: map value (0-100) from which a cell is lethal", 0);
      }));
      s.unknown_cost_value = static_cast<int>(fallback(lr, r, "unknown_cost_value", [&](ParamReader& p) {
        return p.integer("unknown_cost_value", d.unknown_cost_value, "static layer: map value that means unknown");
      }));
      s.trinary_costmap = fallback(lr, r, "trinary_costmap", [&](ParamReader& p) {
        return p.boolean("trinary_costmap", d.trinary_costmap, "static layer: map cells are free, lethal or unknown only");
      });
      s.enabled = fallback(lr, r, "enabled", [&](ParamReader& p) { return p.boolean("enabled", d.enabled, kEnabledDoc); });
      c.static_layer = s;
    } else if (kind == "obstacle") {
      ObstacleLayerConfig o;
      const ObstacleLayerConfig d;
      o.name = layer_name;
      const std::string names = fallback(lr, r, "observation_sources", [](ParamReader& p) {
        return p.string("observation_sources", "", "obstacle layer: the sensors' names, space-separated; each a namespace");
      });
      // The layer's range keys are the defaults of its sources.
      for (const char* key : {"obstacle_range", "raytrace_range", "max_obstacle_height"}) {
        if (&lr != &r && !lr.has(key) && r.has(key)) lr.values().fields[key] = *r.values().get(key);
      }
      std::istringstream in(names);
      std::string source;
      while (in >> source) {
        ParamReader& container = lr.has(source) ? lr : r;
        const ParamValue* sv = container.values().get(source);
        if (!sv || sv->type != ParamValue::Type::kMap) {
          throw ParamError("observation source \"" + source + "\" is listed in " + lr.where("observation_sources") + " but " +
                           container.where(source) + " is not a dict of its parameters");
        }
        container.markRead(source);
        o.sources.push_back(readSource(source, *sv, lr, warn));
        skip.insert(source);
        sub_namespaces.insert(source);
      }
      o.track_unknown_space = fallback(lr, r, "track_unknown_space", [&](ParamReader& p) {
        return p.boolean("track_unknown_space", d.track_unknown_space,
                         "obstacle layer: cells start unknown (else free); static layer: unknown map cells stay unknown");
      });
      o.footprint_clearing_enabled = fallback(lr, r, "footprint_clearing_enabled", [&](ParamReader& p) {
        return p.boolean("footprint_clearing_enabled", d.footprint_clearing_enabled,
                         "obstacle layer: clear the cells under the robot's footprint");
      });
      o.combination_method = static_cast<int>(fallback(lr, r, "combination_method", [&](ParamReader& p) {
        return p.integer("combination_method", d.combination_method, "obstacle layer: 0 overwrite, 1 maximum");
      }));
      o.enabled = fallback(lr, r, "enabled", [&](ParamReader& p) { return p.boolean("enabled", d.enabled, kEnabledDoc); });
      c.obstacle_layer = o;
    } else if (kind == "keepout" || kind == "speed") {
      c.filters.push_back(readFilter(layer_name, type, kind, lr));
      if (&lr != &r) {
        lr.ignored("plugin", "the filter's type (Nav2's key)");
        lr.ignored("type", "the filter's type");
      }
    } else {
      InflationLayerConfig f;
      const InflationLayerConfig d;
      f.name = layer_name;
      f.inflation_radius = fallback(lr, r, "inflation_radius", [&](ParamReader& p) {
        return p.number("inflation_radius", d.inflation_radius, "[m] inflation layer: how far from obstacles cost is added",
                        0.0);
      });
      f.cost_scaling_factor = fallback(lr, r, "cost_scaling_factor", [&](ParamReader& p) {
        return p.number("cost_scaling_factor", d.cost_scaling_factor,
                        "[1/m] inflation layer: how fast the cost falls with distance", 0.0);
      });
      f.inflate_unknown = fallback(lr, r, "inflate_unknown", [&](ParamReader& p) {
        return p.boolean("inflate_unknown", d.inflate_unknown, "inflation layer: inflate around unknown cells too");
      });
      f.enabled = fallback(lr, r, "enabled", [&](ParamReader& p) { return p.boolean("enabled", d.enabled, kEnabledDoc); });
      c.inflation_layer = f;
    }
    if (&lr != &r) lr.reportUnknown(skip);
  }
  // Voxel-layer keys are accepted (the layer is 2D here) but not reported as unknown.
  for (const char* key : {"origin_z", "z_resolution", "z_voxels", "unknown_threshold", "mark_threshold", "publish_voxel_map"}) {
    r.ignored(key, "a voxel layer's key; the obstacle layer is 2D here (the simulated lasers are planar)");
  }
  std::map<std::string, std::string> elsewhere;
  for (const auto& k : kMoveBaseKeys) elsewhere[k] = "move_base";
  r.reportUnknown(sub_namespaces, elsewhere);
  return c;
}

uint8_t staticCost(int8_t value, const StaticLayerConfig& p) {
  const bool unknown = p.unknown_cost_value >= 0 ? value == p.unknown_cost_value : value < 0;
  if (unknown) return p.track_unknown_space ? cost::kNoInformation : cost::kFree;
  if (value >= p.lethal_cost_threshold) return cost::kLethal;
  if (p.trinary_costmap) return cost::kFree;
  const double scaled = std::clamp<double>(value, 0, 100) / p.lethal_cost_threshold * cost::kLethal;
  return static_cast<uint8_t>(std::min<double>(scaled, cost::kLethal));
}

// --- LayeredCostmap ------------------------------------------------------------------------------

LayeredCostmap::LayeredCostmap(const CostmapConfig& config, Warn warn)
    : config_(config),
      warn_(orIgnore(warn)),
      static_(1, 1, config.resolution, {0, 0}),
      obstacle_(1, 1, config.resolution, {0, 0}),
      base_(1, 1, config.resolution, {0, 0}),
      master_(1, 1, config.resolution, {0, 0}) {
  const auto& ob = config_.obstacle_layer;
  obstacle_default_ = ob && ob->track_unknown_space ? cost::kNoInformation : cost::kFree;
  default_value_ = (config_.static_layer && config_.static_layer->track_unknown_space) || (ob && ob->track_unknown_space)
                       ? cost::kNoInformation
                       : cost::kFree;
  if (config_.inflation_layer) {
    inflation_.inscribed_radius = config_.inscribed_radius;
    inflation_.inflation_radius = config_.inflation_layer->inflation_radius;
    inflation_.cost_scaling_factor = config_.inflation_layer->cost_scaling_factor;
    inflation_.inflate_unknown = config_.inflation_layer->inflate_unknown;
  }
  if (config_.rolling_window || !config_.static_layer) {
    resize(std::max(1, static_cast<int>(std::lround(config_.width / config_.resolution))),
           std::max(1, static_cast<int>(std::lround(config_.height / config_.resolution))),
           {config_.origin_x, config_.origin_y}, config_.resolution);
  } else {
    resize(1, 1, {config_.origin_x, config_.origin_y}, config_.resolution);  // sized by the first map
  }
  masks_.resize(config_.filters.size());
  if (ob) {
    observations_.resize(ob->sources.size());
    last_stamp_.assign(ob->sources.size(), std::numeric_limits<double>::quiet_NaN());
    height_warned_.assign(ob->sources.size(), false);
  }
}

void LayeredCostmap::resize(int width, int height, const Eigen::Vector2d& origin, double resolution) {
  obstacle_ = Costmap(width, height, resolution, origin, config_.obstacle_layer ? obstacle_default_ : cost::kFree);
  base_ = Costmap(width, height, resolution, origin, default_value_);
  master_ = Costmap(width, height, resolution, origin, default_value_);
  enableBoxes();
  full_ = true;
}

void LayeredCostmap::enableBoxes() {
  // Only the obstacle layer knows where in a cell its obstacle is; the boxes go with its lethal
  // cells into base_ and master_, where the footprint checks and the inflation near them read them.
  if (!config_.obstacle_layer) return;
  obstacle_.enableBoxes();
  base_.enableBoxes();
  master_.enableBoxes();
}

int LayeredCostmap::sourceIndex(const std::string& name) const {
  if (!config_.obstacle_layer) return -1;
  const auto& s = config_.obstacle_layer->sources;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void LayeredCostmap::setMap(const std::vector<int8_t>& data, int width, int height, const Eigen::Vector2d& origin,
                            double resolution) {
  if (!config_.static_layer) return;
  if (config_.static_layer->first_map_only && map_received_) return;
  if (width <= 0 || height <= 0 || data.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("setMap: " + std::to_string(data.size()) + " cells for " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  const bool same_geometry = static_valid_ && static_.width() == width && static_.height() == height &&
                             std::abs(static_.resolution() - resolution) < 1e-9 && (static_.origin() - origin).norm() < 1e-9;
  Costmap incoming(width, height, resolution, origin);
  for (std::size_t i = 0; i < data.size(); ++i) incoming.costs()[i] = staticCost(data[i], *config_.static_layer);
  if (same_geometry && !config_.rolling_window) {
    // Only the cells that differ from the last map need recomposing.
    CellWindow changed;
    const auto& a = static_.costs();
    const auto& b = incoming.costs();
    for (int y = 0; y < height; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * width;
      if (std::equal(a.begin() + row, a.begin() + row + width, b.begin() + row)) continue;
      int x0 = 0, x1 = width - 1;
      while (a[row + x0] == b[row + x0]) ++x0;
      while (a[row + x1] == b[row + x1]) --x1;
      changed = changed.unite(CellWindow{x0, y, x1 + 1, y + 1});
    }
    dirty_ = dirty_.unite(changed);
  } else if (config_.rolling_window) {
    full_ = true;
  }
  static_ = std::move(incoming);
  static_valid_ = true;
  map_received_ = true;
  for (std::size_t i = 0; i < masks_.size(); ++i) {
    const FilterConfig& f = config_.filters[i];
    if (!masks_[i].valid() || f.mask_topic.empty() || std::abs(masks_[i].resolution() - resolution) < 1e-6) continue;
    char buf[256];
    std::snprintf(buf, sizeof buf, "the map has a resolution of %g m, the mask on %s %g m; the filter is left out until a mask "
                  "of %g m arrives", resolution, f.mask_topic.c_str(), masks_[i].resolution(), resolution);
    filter_errors_.push_back(f.name + ": " + buf);
    masks_[i] = FilterMask();
  }
  if (!config_.rolling_window && !same_geometry &&
      (master_.width() != width || master_.height() != height || std::abs(master_.resolution() - resolution) > 1e-9 ||
       (master_.origin() - origin).norm() > 1e-9)) {
    // The master follows the map's geometry (SLAM grows it); obstacles keep their world places.
    const Costmap old = obstacle_;
    resize(width, height, origin, resolution);
    if (std::abs(old.resolution() - resolution) < 1e-9) {
      const int dx = static_cast<int>(std::lround((old.origin().x() - origin.x()) / resolution));
      const int dy = static_cast<int>(std::lround((old.origin().y() - origin.y()) / resolution));
      for (int y = 0; y < old.height(); ++y) {
        const int ny = y + dy;
        if (ny < 0 || ny >= height) continue;
        for (int x = 0; x < old.width(); ++x) {
          const int nx = x + dx;
          if (nx < 0 || nx >= width) continue;
          obstacle_.setCost({nx, ny}, old.cost({x, y}));
          obstacle_.setBox(obstacle_.index({nx, ny}), old.box(old.index({x, y})));
        }
      }
    }
  } else if (!same_geometry) {
    full_ = true;
  }
}

bool LayeredCostmap::patchMap(const std::vector<int8_t>& data, int x, int y, int width, int height) {
  if (!config_.static_layer || !static_valid_ || width < 0 || height < 0 ||
      data.size() != static_cast<std::size_t>(width) * height || x < 0 || y < 0 || x + width > static_.width() ||
      y + height > static_.height()) {
    return false;
  }
  for (int r = 0; r < height; ++r) {
    uint8_t* row = static_.costs().data() + static_cast<std::size_t>(y + r) * static_.width() + x;
    const int8_t* in = data.data() + static_cast<std::size_t>(r) * width;
    for (int c = 0; c < width; ++c) row[c] = staticCost(in[c], *config_.static_layer);
  }
  if (config_.rolling_window) {
    full_ = true;
  } else {
    dirty_ = dirty_.unite(CellWindow{x, y, x + width, y + height});
  }
  return true;
}

bool LayeredCostmap::addScan(std::size_t source, double stamp, const Eigen::Vector3d& sensor_pose, double sensor_height,
                             const LaserScan& scan) {
  const auto& src = config_.obstacle_layer->sources.at(source);
  if (sensor_height < src.min_obstacle_height || sensor_height > src.max_obstacle_height) {
    if (!height_warned_[source]) {
      height_warned_[source] = true;
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "observation source %s: the sensor is %.3f m high, outside [min_obstacle_height %.3f, "
                    "max_obstacle_height %.3f], so none of its points mark or clear anything",
                    src.name.c_str(), sensor_height, src.min_obstacle_height, src.max_obstacle_height);
      warn_(buf);
    }
    return false;
  }
  last_stamp_[source] = stamp;
  auto& buf = observations_[source];
  if (src.observation_persistence == 0.0) buf.clear();
  buf.push_back({stamp, sensor_pose, scan});
  while (src.observation_persistence > 0.0 && !buf.empty() && stamp - buf.front().stamp > src.observation_persistence) {
    buf.erase(buf.begin());
  }
  return true;
}

std::vector<std::string> LayeredCostmap::staleSources(double now) const {
  std::vector<std::string> stale;
  if (!config_.obstacle_layer) return stale;
  const auto& sources = config_.obstacle_layer->sources;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const ObservationSourceConfig& s = sources[i];
    if (s.expected_update_rate <= 0.0) continue;
    const double age = now - last_stamp_[i];
    if (age <= s.expected_update_rate) continue;
    char why[160];
    if (std::isnan(age)) {  // no scan yet
      std::snprintf(why, sizeof why, "no data yet");
    } else {
      std::snprintf(why, sizeof why, "no data for %.2f s, expected every %.2f s (expected_update_rate)", age,
                    s.expected_update_rate);
    }
    stale.push_back(s.name + " (topic " + s.topic + "): " + why);
  }
  return stale;
}

CellWindow LayeredCostmap::cellsAround(const Eigen::Vector2d& centre, double radius_m) const {
  const Cell lo = obstacle_.worldToCell(centre - Eigen::Vector2d::Constant(radius_m));
  const Cell hi = obstacle_.worldToCell(centre + Eigen::Vector2d::Constant(radius_m));
  return CellWindow{lo.x, lo.y, hi.x + 1, hi.y + 1}.grown(0, obstacle_.width(), obstacle_.height());
}

void LayeredCostmap::compose(const CellWindow& w) {
  const int width = base_.width();
  const bool use_static = config_.static_layer && config_.static_layer->enabled && static_valid_;
  const bool same_grid = use_static && !config_.rolling_window;
  for (int y = w.y0; y < w.y1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * width;
    uint8_t* b = base_.costs().data() + row;
    if (same_grid) {
      std::copy(static_.costs().begin() + row + w.x0, static_.costs().begin() + row + w.x1, b + w.x0);
    } else if (use_static) {
      // Nearest-cell resampling of the map into the rolling window.
      const double wy = base_.origin().y() + (y + 0.5) * base_.resolution();
      const int sy = static_cast<int>(std::floor((wy - static_.origin().y()) / static_.resolution()));
      for (int x = w.x0; x < w.x1; ++x) {
        const double wx = base_.origin().x() + (x + 0.5) * base_.resolution();
        const int sx = static_cast<int>(std::floor((wx - static_.origin().x()) / static_.resolution()));
        b[x] = static_.contains({sx, sy}) ? static_.cost({sx, sy}) : default_value_;
      }
    } else {
      std::fill(b + w.x0, b + w.x1, default_value_);
    }
    if (config_.obstacle_layer && config_.obstacle_layer->enabled) {
      const uint8_t* o = obstacle_.costs().data() + row;
      const bool overwrite = config_.obstacle_layer->combination_method == 0;
      for (int x = w.x0; x < w.x1; ++x) {
        if (o[x] == cost::kNoInformation) {
          base_.setBox(row + x, cell_box::kNoBox);
          continue;
        }
        // updateWithMax; a lethal cell takes the obstacle layer's box only when no other layer
        // has it lethal (a map's lethal cell is whole).
        const bool box = o[x] == cost::kLethal && (overwrite || b[x] != cost::kLethal);
        if (overwrite || b[x] == cost::kNoInformation || o[x] > b[x]) b[x] = o[x];
        base_.setBox(row + x, box ? obstacle_.box(row + x) : cell_box::kNoBox);
      }
    } else if (base_.hasBoxes()) {
      for (int x = w.x0; x < w.x1; ++x) base_.setBox(row + x, cell_box::kNoBox);
    }
  }
  applyKeepout(w);
}

bool LayeredCostmap::filterUsable(std::size_t i) const {
  const FilterConfig& f = config_.filters[i];
  return f.enabled && f.error.empty() && masks_[i].valid() && std::abs(masks_[i].resolution() - master_.resolution()) < 1e-6;
}

void LayeredCostmap::applyKeepout(const CellWindow& w) {
  for (std::size_t i = 0; i < masks_.size(); ++i) {
    if (config_.filters[i].kind != FilterConfig::Kind::kKeepout || !filterUsable(i)) continue;
    const FilterMask& mask = masks_[i];
    // Same resolution (filterUsable): the costmap's cell x lies on the mask's column x + dx.
    const double res = base_.resolution();
    const int dx = mask.column(base_.origin().x() + 0.5 * res), dy = mask.row(base_.origin().y() + 0.5 * res);
    for (int y = w.y0; y < w.y1; ++y) {
      const int my = y + dy;
      if (my < 0 || my >= mask.height()) continue;
      const int8_t* m = mask.data().data() + static_cast<std::size_t>(my) * mask.width();
      uint8_t* b = base_.costs().data() + static_cast<std::size_t>(y) * base_.width();
      for (const auto& [begin, end] : mask.runs(my)) {
        const int x0 = std::max(begin - dx, w.x0), x1 = std::min(end - dx, w.x1);
        for (int x = x0; x < x1; ++x) {
          const uint8_t c = keepoutCost(m[x + dx]);
          const bool raised = b[x] == cost::kNoInformation || c > b[x];
          if (raised) b[x] = c;  // Nav2's KeepoutFilter rule
          // A zone's lethal cell is whole, also where the laser marks it: not the box of its returns.
          if (raised || c == cost::kLethal) base_.setBox(static_cast<std::size_t>(y) * base_.width() + x, cell_box::kNoBox);
        }
      }
    }
  }
}

void LayeredCostmap::setFilterMask(std::size_t index, const std::vector<int8_t>& data, int width, int height,
                                   const Eigen::Vector2d& origin, double resolution) {
  const FilterConfig& f = config_.filters.at(index);
  const bool sized = !config_.static_layer || config_.rolling_window || map_received_;
  if (sized && std::abs(resolution - master_.resolution()) > 1e-6) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "the mask's resolution is %g m, the costmap's %g m: draw the mask at the costmap's",
                  resolution, master_.resolution());
    throw std::invalid_argument(buf);
  }
  FilterMask mask;
  mask.set(data, width, height, origin, resolution);
  masks_[index] = std::move(mask);
  if (f.kind == FilterConfig::Kind::kKeepout) full_ = true;
}

std::vector<std::string> LayeredCostmap::takeFilterErrors() {
  std::vector<std::string> out;
  out.swap(filter_errors_);
  return out;
}

std::string LayeredCostmap::keepoutZoneAt(const Eigen::Vector2d& p) const {
  for (std::size_t i = 0; i < masks_.size(); ++i) {
    if (config_.filters[i].kind != FilterConfig::Kind::kKeepout || !filterUsable(i)) continue;
    if (keepoutCost(masks_[i].valueAt(p)) < cost::kLethal) continue;
    const int zone = masks_[i].zoneAt(p);
    return (zone >= 0 ? masks_[i].zoneNames()[zone] : std::string("a zone")) + " (filter " + config_.filters[i].name + ")";
  }
  return "";
}

LayeredCostmap::SpeedLimit LayeredCostmap::speedLimitAt(const Eigen::Vector3d& pose) const {
  SpeedLimit out;
  std::vector<Cell> cells;
  for (std::size_t i = 0; i < masks_.size(); ++i) {
    const FilterConfig& f = config_.filters[i];
    if (f.kind != FilterConfig::Kind::kSpeed || !filterUsable(i)) continue;
    if (cells.empty()) cells = footprintCells(master_, pose, config_.footprint);
    for (const Cell& c : cells) {
      const Eigen::Vector2d p = master_.cellCenter(c);
      const int8_t v = masks_[i].valueAt(p);
      if (v <= 0) continue;
      const double limit = f.base + f.multiplier * v;
      if (out.limited && (out.percent != f.percent || limit >= out.value)) continue;
      const int zone = masks_[i].zoneAt(p);
      out = SpeedLimit{true, limit, f.percent, (zone >= 0 ? masks_[i].zoneNames()[zone] : "a zone") + " (filter " + f.name + ")"};
    }
  }
  return out;
}

CellWindow LayeredCostmap::update(const Eigen::Vector3d& robot_pose) {
  if (config_.rolling_window) {
    const Eigen::Vector2d origin(robot_pose.x() - master_.width() * master_.resolution() / 2.0,
                                 robot_pose.y() - master_.height() * master_.resolution() / 2.0);
    const Eigen::Vector2d before = obstacle_.origin();
    obstacle_.moveOrigin(origin, obstacle_default_);
    if ((obstacle_.origin() - before).norm() > 1e-12) {
      base_ = Costmap(obstacle_.width(), obstacle_.height(), obstacle_.resolution(), obstacle_.origin(), default_value_);
      master_ = Costmap(obstacle_.width(), obstacle_.height(), obstacle_.resolution(), obstacle_.origin(), default_value_);
      enableBoxes();
      full_ = true;
    }
  }
  const auto& ob = config_.obstacle_layer;
  if (ob && ob->enabled) {
    std::vector<Cell> too_close;
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      const auto& src = ob->sources[i];
      ObservationSourceParams p;
      p.obstacle_range = src.obstacle_range;
      p.raytrace_range = src.raytrace_range;
      p.raytrace_end_margin = src.raytrace_end_margin;
      p.marking = src.marking;
      p.clearing = src.clearing;
      p.inf_is_valid = src.inf_is_valid;
      p.too_close_is_obstacle = src.too_close_is_obstacle;
      for (const auto& obs : observations_[i]) {
        // Clearing and marking in one pass per scan, as ObstacleLayer does per cloud.
        updateWithScan(obstacle_, obs.pose, obs.scan, p, &too_close);
        const double reach = std::min(std::max(src.raytrace_range, src.obstacle_range), obs.scan.range_max_m);
        dirty_ = dirty_.unite(cellsAround(obs.pose.head<2>(), reach + obstacle_.resolution()));
      }
      // A scan marks once (costmap_2d re-marks only what observation_persistence keeps).
      if (src.observation_persistence == 0.0) observations_[i].clear();
    }
    if (ob->footprint_clearing_enabled) {
      for (const Cell& cell : footprintCells(obstacle_, robot_pose, config_.footprint)) {
        if (!obstacle_.contains(cell)) continue;
        // A return outside the footprint is not the robot's own body, though its cell is under the
        // outline: beside a post in a gap its mark must stay for the footprint checks.
        const uint32_t box = obstacle_.box(obstacle_.index(cell));
        if (box != cell_box::kNoBox && obstacle_.cost(cell) == cost::kLethal &&
            !footprintMeetsRect(robot_pose, config_.footprint, obstacle_.obstacleBounds(cell, 0.0))) {
          continue;
        }
        obstacle_.setCost(cell, cost::kFree);
      }
      // What covers the laser is not the robot's own body seen by its sensor, which is what
      // footprint clearing is for: a person who walked into the robot stays marked where it is.
      for (const Cell& cell : too_close) {
        obstacle_.setCost(cell, cost::kLethal);
        obstacle_.setBox(obstacle_.index(cell), cell_box::kNoBox);
      }
      dirty_ = dirty_.unite(cellsAround(robot_pose.head<2>(), config_.circumscribed_radius + obstacle_.resolution()));
    }
  }
  for (std::size_t i = 0; i < masks_.size(); ++i) {
    const FilterConfig& f = config_.filters[i];
    if (!f.error.empty() || f.zones.empty() || (masks_[i].valid() && std::abs(masks_[i].resolution() - master_.resolution()) < 1e-6)) {
      continue;
    }
    masks_[i].setPolygons(f.zones, master_.resolution());  // validated when read
    full_ = true;
  }
  const int w = master_.width(), h = master_.height();
  CellWindow window = full_ ? CellWindow{0, 0, w, h} : dirty_.grown(0, w, h);
  if (!window.empty()) {
    compose(window);
    const bool inflating = config_.inflation_layer && config_.inflation_layer->enabled;
    const int reach = inflating ? static_cast<int>(std::ceil(inflation_.inflation_radius / master_.resolution())) : 0;
    window = window.grown(reach, w, h);  // cells whose inflation the change may alter
    if (inflating) {
      inflateWindow(base_, master_, window, inflation_);
      if (base_.hasBoxes()) {
        refineNearBoxes(base_, master_, window, inflation_, contactRadius(config_.footprint));
      }
    } else {
      for (int y = window.y0; y < window.y1; ++y) {
        const std::size_t row = static_cast<std::size_t>(y) * w;
        std::copy(base_.costs().begin() + row + window.x0, base_.costs().begin() + row + window.x1,
                  master_.costs().begin() + row + window.x0);
        for (int x = window.x0; x < window.x1; ++x) master_.setBox(row + x, base_.box(row + x));
      }
    }
  }
  dirty_ = CellWindow{};
  full_ = false;
  return window;
}

uint8_t LayeredCostmap::roomyCost() const {
  if (!config_.inflation_layer || !config_.inflation_layer->enabled) return contactCost();
  const uint8_t c = core::contactCost(inflation_, master_.resolution(), contactRadius(config_.footprint), kRoomyClearance);
  return c > cost::kFree ? std::min(c, contactCost()) : contactCost();
}

uint8_t LayeredCostmap::contactCost() const {
  return config_.inflation_layer && config_.inflation_layer->enabled
             ? core::contactCost(inflation_, master_.resolution(), contactRadius(config_.footprint))
             : cost::kInscribed;
}

void LayeredCostmap::resetObstacles(const std::optional<Eigen::Vector3d>& keep) {
  const Costmap old = obstacle_;
  obstacle_.fill(obstacle_default_);
  if (keep) {
    const double half = keep->z() / 2.0, res = obstacle_.resolution();
    const int x0 = static_cast<int>(std::floor((keep->x() - half - obstacle_.origin().x()) / res));
    const int y0 = static_cast<int>(std::floor((keep->y() - half - obstacle_.origin().y()) / res));
    const int x1 = static_cast<int>(std::ceil((keep->x() + half - obstacle_.origin().x()) / res));
    const int y1 = static_cast<int>(std::ceil((keep->y() + half - obstacle_.origin().y()) / res));
    for (int y = std::max(y0, 0); y < std::min(y1, obstacle_.height()); ++y) {
      for (int x = std::max(x0, 0); x < std::min(x1, obstacle_.width()); ++x) {
        obstacle_.setCost({x, y}, old.cost({x, y}));
        obstacle_.setBox(obstacle_.index({x, y}), old.box(old.index({x, y})));
      }
    }
  }
  full_ = true;
}

}  // namespace core
}  // namespace mbot
