// Bindings of the log-odds occupancy grid, Bresenham lines, grid ray casting and the log of a
// followed map's updates.
#include "bindings.h"

#include <tuple>

#include "mbot_slam_navigation/core/bresenham.h"
#include "mbot_slam_navigation/core/grid_raycast.h"
#include "mbot_slam_navigation/core/map_updates.h"
#include "mbot_slam_navigation/core/occupancy_grid.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindGrid(py::module& m) {
  py::class_<LogOddsModel>(m, "_LogOddsModel")
      .def(py::init<>())
      .def_static("from_probabilities", &LogOddsModel::fromProbabilities, py::arg("p_hit"), py::arg("p_miss"))
      .def_readwrite("hit", &LogOddsModel::hit)
      .def_readwrite("miss", &LogOddsModel::miss)
      .def_readwrite("min", &LogOddsModel::min)
      .def_readwrite("max", &LogOddsModel::max);

  py::class_<OccupancyGrid>(m, "_OccupancyGrid")
      .def(py::init<int, int, double, const Eigen::Vector2d&, const LogOddsModel&>(), py::arg("width"),
           py::arg("height"), py::arg("resolution"), py::arg("origin"), py::arg("model") = LogOddsModel())
      .def_property_readonly("width", &OccupancyGrid::width)
      .def_property_readonly("height", &OccupancyGrid::height)
      .def_property_readonly("resolution", &OccupancyGrid::resolution)
      .def_property_readonly("origin", &OccupancyGrid::origin)
      .def("contains", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.contains(toCell(c)); })
      .def("world_to_cell",
           [](const OccupancyGrid& g, const Eigen::Vector2d& p) {
             const Cell c = g.worldToCell(p);
             return std::make_pair(c.x, c.y);
           })
      .def("cell_center", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.cellCenter(toCell(c)); })
      .def("log_odds", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.logOdds(toCell(c)); })
      .def("probability", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.probability(toCell(c)); })
      .def("observed", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.observed(toCell(c)); })
      .def("set_log_odds", [](OccupancyGrid& g, std::pair<int, int> c, float l) { g.setLogOdds(toCell(c), l); })
      .def("integrate_beam", &OccupancyGrid::integrateBeam, py::arg("start"), py::arg("end"), py::arg("hit"))
      .def(
          "integrate_scan",
          [](OccupancyGrid& g, const Eigen::Vector3d& pose, double angle_min, double angle_increment,
             double range_min, double range_max, const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges,
             double usable_range) {
            return g.integrateScan(pose, toScan(angle_min, angle_increment, range_min, range_max, ranges), usable_range);
          },
          py::arg("pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"),
          py::arg("range_max"), py::arg("ranges"), py::arg("usable_range"))
      .def("grow_to_include", &OccupancyGrid::growToInclude, py::arg("point"), py::arg("margin"))
      .def("observed_count", &OccupancyGrid::observedCount)
      .def("ros_data", [](const OccupancyGrid& g) {
        const std::vector<int8_t> data = g.toRosData();
        py::array_t<int8_t> out({g.height(), g.width()});
        std::copy(data.begin(), data.end(), out.mutable_data());
        return out;
      });

  py::class_<MapUpdateLog>(m, "_MapUpdateLog")
      .def(py::init<>())
      .def(
          "update",
          [](MapUpdateLog& log, int64_t stamp_ns, int x, int y, int width, int height,
             const py::array_t<int8_t, py::array::c_style | py::array::forcecast>& data) {
            return log.update(MapUpdate{stamp_ns, GridWindow{x, y, width, height},
                                        std::vector<int8_t>(data.data(), data.data() + data.size())});
          },
          py::arg("stamp_ns"), py::arg("x"), py::arg("y"), py::arg("width"), py::arg("height"), py::arg("data"))
      .def(
          "whole",
          [](MapUpdateLog& log, int64_t stamp_ns, int64_t now_ns) -> py::object {
            const auto newer = log.whole(stamp_ns, now_ns);
            if (!newer) return py::none();
            py::list out;
            for (const MapUpdate& u : *newer) {
              py::array_t<int8_t> data(static_cast<py::ssize_t>(u.data.size()));
              std::copy(u.data.begin(), u.data.end(), data.mutable_data());
              out.append(py::make_tuple(u.window.x, u.window.y, u.window.width, u.window.height, data));
            }
            return std::move(out);
          },
          py::arg("stamp_ns"), py::arg("now_ns"));

  m.def(
      "_bresenham_line",
      [](std::pair<int, int> a, std::pair<int, int> b) {
        std::vector<std::pair<int, int>> out;
        for (const Cell& c : mbot::core::bresenhamLine(toCell(a), toCell(b))) out.emplace_back(c.x, c.y);
        return out;
      },
      py::arg("start"), py::arg("end"));

  m.def(
      "_cast_rays",
      [](const OccupancyGrid& g, const Eigen::Vector2d& origin,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& angles, double max_range,
         double occupied_probability) {
        py::array_t<double> out(angles.size());
        double* o = out.mutable_data();
        const double* a = angles.data();
        {
          py::gil_scoped_release release;  // pure C++ loop: let other Python threads run
          for (py::ssize_t i = 0; i < angles.size(); ++i) {
            o[i] = mbot::core::castRay(g, origin, a[i], max_range, occupied_probability);
          }
        }
        return out;
      },
      py::arg("grid"), py::arg("origin"), py::arg("angles"), py::arg("max_range"),
      py::arg("occupied_probability") = 0.5);
}

}  // namespace bindings
}  // namespace mbot
