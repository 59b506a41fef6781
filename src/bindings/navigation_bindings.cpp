// Bindings of move_base's configuration and costmap layers (the same C++ the roscpp move_base
// runs), for the Python nodes that read parameters and for the tests.
#include "bindings.h"

#include <pybind11/functional.h>

#include "mbot_slam_navigation/core/layered_costmap.h"
#include "mbot_slam_navigation/core/move_base_config.h"
#include "mbot_slam_navigation/core/params.h"
#include "mbot_slam_navigation/core/slam_config.h"
#include "mbot_slam_navigation/core/trajectory_controller.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

namespace {

ParamValue toParam(const py::handle& o) {
  if (o.is_none()) return ParamValue();
  if (py::isinstance<py::bool_>(o)) return ParamValue::ofBool(o.cast<bool>());
  if (py::isinstance<py::int_>(o)) return ParamValue::ofInt(o.cast<long>());
  if (py::isinstance<py::float_>(o)) return ParamValue::ofDouble(o.cast<double>());
  if (py::isinstance<py::str>(o)) return ParamValue::ofString(o.cast<std::string>());
  if (py::isinstance<py::dict>(o)) {
    std::map<std::string, ParamValue> fields;
    for (const auto& [k, v] : o.cast<py::dict>()) fields[py::str(k).cast<std::string>()] = toParam(v);
    return ParamValue::ofMap(std::move(fields));
  }
  if (py::isinstance<py::list>(o) || py::isinstance<py::tuple>(o)) {
    std::vector<ParamValue> items;
    for (const auto& v : o) items.push_back(toParam(v));
    return ParamValue::ofList(std::move(items));
  }
  return ParamValue::ofString(py::str(o).cast<std::string>());  // what XmlRpc would not carry either
}

py::object fromParam(const ParamValue& v) {
  switch (v.type) {
    case ParamValue::Type::kNone: return py::none();
    case ParamValue::Type::kBool: return py::bool_(v.b);
    case ParamValue::Type::kInt: return py::int_(v.i);
    case ParamValue::Type::kDouble: return py::float_(v.d);
    case ParamValue::Type::kString: return py::str(v.s);
    case ParamValue::Type::kList: {
      py::list l;
      for (const auto& i : v.items) l.append(fromParam(i));
      return std::move(l);
    }
    case ParamValue::Type::kMap: {
      py::dict d;
      for (const auto& [k, i] : v.fields) d[py::str(k)] = fromParam(i);
      return std::move(d);
    }
  }
  return py::none();
}

Warn warnOf(py::object warn) {
  if (warn.is_none()) return Warn();
  return [warn](const std::string& text) {
    py::gil_scoped_acquire gil;
    warn(text);
  };
}

}  // namespace

void bindNavigation(py::module& m) {
  py::register_exception<ParamError>(m, "ParamError", PyExc_ValueError);
  m.def("nearest_key", [](const std::string& key, const std::vector<std::string>& known) -> py::object {
    const std::string k = nearestKey(key, known);
    return k.empty() ? py::object(py::none()) : py::object(py::str(k));
  }, "The known key closest in spelling to key, or None when nothing is close.", py::arg("key"), py::arg("known"));

  py::class_<ParamReader>(m, "ParamReader")
      .def(py::init([](py::object values, const std::string& ns, py::object warn) {
             return ParamReader(toParam(values), ns, warnOf(warn));
           }),
           py::arg("values"), py::arg("ns"), py::arg("warn"))
      .def_property_readonly("ns", &ParamReader::ns)
      .def_property_readonly("read_keys", &ParamReader::readKeys)
      .def_property_readonly("values", [](const ParamReader& r) { return fromParam(r.values()); })
      .def("where", &ParamReader::where)
      .def("has", &ParamReader::has)
      .def("warn", &ParamReader::warn)
      .def("raw", [](ParamReader& r, const std::string& key, py::object fallback, const char* doc, const char* type) {
             return fromParam(r.raw(key, toParam(fallback), doc, type));
           }, py::arg("key"), py::arg("default") = py::none(), py::arg("doc") = nullptr, py::arg("type") = "any")
      .def("number", [](ParamReader& r, const std::string& key, double fallback, const char* doc, std::optional<double> minimum,
                        bool positive) { return r.number(key, fallback, doc, minimum, positive); },
           py::arg("key"), py::arg("default"), py::arg("doc") = nullptr, py::arg("minimum") = py::none(),
           py::arg("positive") = false)
      .def("integer", [](ParamReader& r, const std::string& key, long fallback, const char* doc, std::optional<long> minimum) {
             return r.integer(key, fallback, doc, minimum);
           }, py::arg("key"), py::arg("default"), py::arg("doc") = nullptr, py::arg("minimum") = py::none())
      .def("boolean", &ParamReader::boolean, py::arg("key"), py::arg("default"), py::arg("doc") = nullptr)
      .def("string", &ParamReader::string, py::arg("key"), py::arg("default"), py::arg("doc") = nullptr)
      .def("frame", &ParamReader::frame, py::arg("key"), py::arg("default"), py::arg("doc") = nullptr)
      .def("ignored", &ParamReader::ignored, py::arg("key"), py::arg("why"))
      .def("deprecated", &ParamReader::deprecated, py::arg("new"), py::arg("old"), py::arg("default"),
           py::arg("doc") = nullptr)
      .def("report_unknown", &ParamReader::reportUnknown, py::arg("skip") = std::set<std::string>(),
           py::arg("elsewhere") = std::map<std::string, std::string>());

  // The reads of every ParamReader on this thread while the catalog is open, for the reference
  // pages (tools/node_docs.py): `with ParamCatalog() as c: ...; c.declarations`.
  py::class_<ParamCatalog>(m, "ParamCatalog")
      .def(py::init<>())
      .def("__enter__", [](ParamCatalog& c) -> ParamCatalog& { return c; }, py::return_value_policy::reference)
      .def("__exit__", [](ParamCatalog& c, py::object, py::object, py::object) {
        c.close();
        return false;
      })
      .def_property_readonly("declarations", [](const ParamCatalog& c) {
        py::list out;
        for (const auto& d : c.declarations()) {
          py::dict e;
          e["ns"] = d.ns;
          e["key"] = d.key;
          e["type"] = d.type;
          e["default"] = d.default_repr;
          e["bounds"] = d.bounds;
          e["unit"] = d.unit;
          e["meaning"] = d.meaning;
          out.append(e);
        }
        return out;
      });

  py::class_<ObservationSourceConfig>(m, "ObservationSourceConfig")
      .def_readonly("name", &ObservationSourceConfig::name)
      .def_readonly("topic", &ObservationSourceConfig::topic)
      .def_readonly("sensor_frame", &ObservationSourceConfig::sensor_frame)
      .def_readonly("observation_persistence", &ObservationSourceConfig::observation_persistence)
      .def_readonly("expected_update_rate", &ObservationSourceConfig::expected_update_rate)
      .def_readonly("clearing", &ObservationSourceConfig::clearing)
      .def_readonly("marking", &ObservationSourceConfig::marking)
      .def_readonly("max_obstacle_height", &ObservationSourceConfig::max_obstacle_height)
      .def_readonly("min_obstacle_height", &ObservationSourceConfig::min_obstacle_height)
      .def_readonly("obstacle_range", &ObservationSourceConfig::obstacle_range)
      .def_readonly("raytrace_range", &ObservationSourceConfig::raytrace_range)
      .def_readonly("inf_is_valid", &ObservationSourceConfig::inf_is_valid)
      .def_readonly("too_close_is_obstacle", &ObservationSourceConfig::too_close_is_obstacle);
  py::class_<StaticLayerConfig>(m, "StaticLayerConfig")
      .def(py::init<>())
      .def_readwrite("name", &StaticLayerConfig::name)
      .def_readwrite("map_topic", &StaticLayerConfig::map_topic)
      .def_readwrite("track_unknown_space", &StaticLayerConfig::track_unknown_space)
      .def_readwrite("trinary_costmap", &StaticLayerConfig::trinary_costmap)
      .def_readwrite("lethal_cost_threshold", &StaticLayerConfig::lethal_cost_threshold)
      .def_readwrite("unknown_cost_value", &StaticLayerConfig::unknown_cost_value)
      .def_readwrite("first_map_only", &StaticLayerConfig::first_map_only);
  py::class_<ObstacleLayerConfig>(m, "ObstacleLayerConfig")
      .def_readonly("name", &ObstacleLayerConfig::name)
      .def_property_readonly("sources", [](const ObstacleLayerConfig& o) {
        py::dict d;
        for (const auto& s : o.sources) d[py::str(s.name)] = s;
        return d;
      })
      .def_readonly("track_unknown_space", &ObstacleLayerConfig::track_unknown_space)
      .def_readonly("combination_method", &ObstacleLayerConfig::combination_method);
  py::class_<InflationLayerConfig>(m, "InflationLayerConfig")
      .def_readonly("name", &InflationLayerConfig::name)
      .def_readonly("inflation_radius", &InflationLayerConfig::inflation_radius)
      .def_readonly("cost_scaling_factor", &InflationLayerConfig::cost_scaling_factor)
      .def_readonly("inflate_unknown", &InflationLayerConfig::inflate_unknown);
  py::class_<FilterConfig>(m, "FilterConfig")
      .def_readonly("name", &FilterConfig::name)
      .def_readonly("type", &FilterConfig::type)
      .def_property_readonly("kind", [](const FilterConfig& f) { return f.kind == FilterConfig::Kind::kSpeed ? "speed" : "keepout"; })
      .def_readonly("mask_topic", &FilterConfig::mask_topic)
      .def_property_readonly("zones", [](const FilterConfig& f) {
        py::list out;
        for (const auto& z : f.zones) out.append(py::make_tuple(z.name, z.points));
        return out;
      })
      .def_readonly("error", &FilterConfig::error);
  py::class_<CostmapConfig>(m, "CostmapConfig")
      .def_readonly("name", &CostmapConfig::name)
      .def_readonly("global_frame", &CostmapConfig::global_frame)
      .def_readonly("robot_base_frame", &CostmapConfig::robot_base_frame)
      .def_readonly("transform_tolerance", &CostmapConfig::transform_tolerance)
      .def_readonly("update_frequency", &CostmapConfig::update_frequency)
      .def_readonly("publish_frequency", &CostmapConfig::publish_frequency)
      .def_readonly("rolling_window", &CostmapConfig::rolling_window)
      .def_readonly("resolution", &CostmapConfig::resolution)
      .def_readonly("footprint", &CostmapConfig::footprint)
      .def_readonly("inscribed_radius", &CostmapConfig::inscribed_radius)
      .def_readonly("circumscribed_radius", &CostmapConfig::circumscribed_radius)
      .def_readonly("layers", &CostmapConfig::layers)
      .def_readonly("static", &CostmapConfig::static_layer)
      .def_readonly("obstacle", &CostmapConfig::obstacle_layer)
      .def_readonly("inflation", &CostmapConfig::inflation_layer)
      .def_readonly("filters", &CostmapConfig::filters);
  m.def("read_costmap_config", [](const std::string& name, py::object values, py::object warn, const std::string& ns_prefix) {
    return readCostmapConfig(name, toParam(values), warnOf(warn), ns_prefix);
  }, py::arg("name"), py::arg("values"), py::arg("warn"), py::arg("ns_prefix") = "");
  m.def("static_cost", &staticCost, py::arg("value"), py::arg("params"));

  py::class_<LayeredCostmap>(m, "LayeredCostmap")
      .def(py::init([](const CostmapConfig& c, py::object warn) { return std::make_unique<LayeredCostmap>(c, warnOf(warn)); }),
           py::arg("config"), py::arg("warn"))
      .def_property_readonly("ready", &LayeredCostmap::ready)
      .def("set_map", [](LayeredCostmap& l, py::array_t<int8_t, py::array::c_style | py::array::forcecast> data,
                         const Eigen::Vector2d& origin, double resolution) {
             if (data.ndim() != 2) throw std::invalid_argument("set_map: data must be 2D (rows = y)");
             l.setMap(std::vector<int8_t>(data.data(), data.data() + data.size()), static_cast<int>(data.shape(1)),
                      static_cast<int>(data.shape(0)), origin, resolution);
           }, py::arg("data"), py::arg("origin"), py::arg("resolution"))
      .def("add_scan", [](LayeredCostmap& l, const std::string& source, double stamp, const Eigen::Vector3d& pose, double height,
                          double angle_min, double angle_increment, double range_min, double range_max,
                          const std::vector<float>& ranges) {
             const int i = l.sourceIndex(source);
             if (i < 0) throw std::invalid_argument("no observation source " + source);
             LaserScan scan;
             scan.angle_min_rad = angle_min;
             scan.angle_increment_rad = angle_increment;
             scan.range_min_m = range_min;
             scan.range_max_m = range_max;
             scan.ranges_m = ranges;
             return l.addScan(static_cast<std::size_t>(i), stamp, pose, height, scan);
           })
      .def("stale_sources", &LayeredCostmap::staleSources)
      .def("update", [](LayeredCostmap& l, const Eigen::Vector3d& pose) {
        const CellWindow w = l.update(pose);
        return py::make_tuple(w.x0, w.y0, w.x1, w.y1);
      }, "One update; returns the changed window (x0, y0, x1, y1) in cells.")
      .def("reset_obstacles", &LayeredCostmap::resetObstacles, py::arg("keep") = std::nullopt)
      .def("master", [](const LayeredCostmap& l) { return l.master(); }, "A copy of the inflated master grid (_Costmap).")
      .def("set_filter_mask", [](LayeredCostmap& l, std::size_t index, py::array_t<int8_t, py::array::c_style | py::array::forcecast> data,
                                 const Eigen::Vector2d& origin, double resolution) {
             if (data.ndim() != 2) throw std::invalid_argument("set_filter_mask: data must be 2D (rows = y)");
             l.setFilterMask(index, std::vector<int8_t>(data.data(), data.data() + data.size()), static_cast<int>(data.shape(1)),
                             static_cast<int>(data.shape(0)), origin, resolution);
           }, py::arg("index"), py::arg("data"), py::arg("origin"), py::arg("resolution"))
      .def("patch_map", [](LayeredCostmap& l, py::array_t<int8_t, py::array::c_style | py::array::forcecast> data, int x, int y) {
             if (data.ndim() != 2) throw std::invalid_argument("patch_map: data must be 2D (rows = y)");
             return l.patchMap(std::vector<int8_t>(data.data(), data.data() + data.size()), x, y,
                               static_cast<int>(data.shape(1)), static_cast<int>(data.shape(0)));
           }, py::arg("data"), py::arg("x"), py::arg("y"))
      .def("take_filter_errors", &LayeredCostmap::takeFilterErrors)
      .def("keepout_zone_at", &LayeredCostmap::keepoutZoneAt, py::arg("point"))
      .def("speed_limit_at", [](const LayeredCostmap& l, const Eigen::Vector3d& pose) {
        const auto s = l.speedLimitAt(pose);
        return s.limited ? py::object(py::make_tuple(s.value, s.percent, s.zone)) : py::object(py::none());
      }, py::arg("pose"), "(limit, percent, zone) under the footprint at pose, or None.");

  py::class_<LocalPlannerRosParams>(m, "LocalPlannerRosParams")
      .def_readonly("xy_goal_tolerance", &LocalPlannerRosParams::xy_goal_tolerance)
      .def_readonly("yaw_goal_tolerance", &LocalPlannerRosParams::yaw_goal_tolerance)
      .def_readonly("latch_xy_goal_tolerance", &LocalPlannerRosParams::latch_xy_goal_tolerance)
      .def_readonly("prune_plan", &LocalPlannerRosParams::prune_plan)
      .def_readonly("max_rotational_vel", &LocalPlannerRosParams::max_rotational_vel);
  m.def("read_local_planner_params", [](py::object values, const std::string& ns, py::object warn, double frequency) {
    LocalPlannerParams p;
    LocalPlannerRosParams r;
    readLocalPlannerParams(toParam(values), ns, warnOf(warn), frequency, p, r);
    return py::make_tuple(p, r);
  }, py::arg("values"), py::arg("ns"), py::arg("warn"), py::arg("controller_frequency"));
  m.def("prune_plan", &prunePlan, py::arg("plan"), py::arg("pose"));

  py::class_<RecoveryConfig>(m, "RecoveryConfig")
      .def_readonly("name", &RecoveryConfig::name)
      .def_readonly("type", &RecoveryConfig::type)
      .def_readonly("reset_distance", &RecoveryConfig::reset_distance)
      .def_readonly("affected_maps", &RecoveryConfig::affected_maps)
      .def_readonly("distance", &RecoveryConfig::distance)
      .def_readonly("speed", &RecoveryConfig::speed);
  py::class_<MoveBaseConfig>(m, "MoveBaseConfig")
      .def_readonly("controller_frequency", &MoveBaseConfig::controller_frequency)
      .def_readonly("planner_frequency", &MoveBaseConfig::planner_frequency)
      .def_readonly("controller_patience", &MoveBaseConfig::controller_patience)
      .def_readonly("oscillation_timeout", &MoveBaseConfig::oscillation_timeout)
      .def_readonly("global_ns", &MoveBaseConfig::global_ns)
      .def_readonly("local_ns", &MoveBaseConfig::local_ns)
      .def_property_readonly("use_astar", [](const MoveBaseConfig& c) { return c.planner.use_astar; })
      .def_property_readonly("lethal_cost", [](const MoveBaseConfig& c) { return c.planner.lethal_cost; })
      .def_readonly("local", &MoveBaseConfig::local)
      .def_readonly("recoveries", &MoveBaseConfig::recoveries);
  m.def("read_move_base_config", [](py::object values, const std::string& ns, py::object warn, double circumscribed) {
    return readMoveBaseConfig(toParam(values), ns, warnOf(warn), circumscribed);
  }, py::arg("values"), py::arg("ns"), py::arg("warn"), py::arg("circumscribed_radius"));

  py::class_<SlamConfig>(m, "SlamConfig")
      .def_readonly("base_frame", &SlamConfig::base_frame)
      .def_readonly("odom_frame", &SlamConfig::odom_frame)
      .def_readonly("map_frame", &SlamConfig::map_frame)
      .def_readonly("map_update_interval", &SlamConfig::map_update_interval)
      .def_readonly("occ_thresh", &SlamConfig::occ_thresh)
      .def_readonly("backend", &SlamConfig::backend)
      .def_readonly("rbpf", &SlamConfig::rbpf)
      .def_readonly("graph", &SlamConfig::graph);
  m.def("read_slam_config", [](py::object values, const std::string& ns, py::object warn, double default_max_range) {
    std::vector<std::string> unknown;
    SlamConfig c = readSlamConfig(toParam(values), ns, warnOf(warn), default_max_range, &unknown);
    return std::make_pair(c, unknown);
  }, "slam_gmapping's parameters (core/slam_config.h) and the keys no one reads.", py::arg("values"), py::arg("ns"),
     py::arg("warn"), py::arg("default_max_range"));
}

}  // namespace bindings
}  // namespace mbot
