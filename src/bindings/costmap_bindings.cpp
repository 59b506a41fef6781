// Bindings of costmaps, inflation, path lengths, tours and the global planner.
#include "bindings.h"

#include <tuple>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/local_planner.h"
#include "mbot_slam_navigation/core/global_planner.h"
#include "mbot_slam_navigation/core/inflation_layer.h"
#include "mbot_slam_navigation/core/obstacle_layer.h"
#include "mbot_slam_navigation/core/path_lengths.h"
#include "mbot_slam_navigation/core/tour.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindCostmaps(py::module& m) {
  m.def(
      "_inflate",
      [](py::array_t<uint8_t, py::array::c_style> costs, double resolution, double inscribed_radius,
         double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
        if (costs.ndim() != 2) throw std::invalid_argument("costs must be a 2D array (rows = y)");
        mbot::core::Costmap map(static_cast<int>(costs.shape(1)), static_cast<int>(costs.shape(0)), resolution, {0, 0});
        std::copy(costs.data(), costs.data() + costs.size(), map.costs().begin());
        mbot::core::InflationParams p;
        p.inscribed_radius = inscribed_radius;
        p.inflation_radius = inflation_radius;
        p.cost_scaling_factor = cost_scaling_factor;
        p.inflate_unknown = inflate_unknown;
        {
          py::gil_scoped_release release;
          mbot::core::inflate(map, p);
        }
        std::copy(map.costs().begin(), map.costs().end(), costs.mutable_data());
      },
      py::arg("costs"), py::arg("resolution"), py::arg("inscribed_radius"), py::arg("inflation_radius"),
      py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false);

  using mbot::core::Costmap;
  py::class_<Costmap>(m, "_Costmap")
      .def(py::init([](const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& costs, double resolution,
                       const Eigen::Vector2d& origin) {
             if (costs.ndim() != 2) throw std::invalid_argument("costs must be a 2D array (rows = y)");
             auto map = std::make_unique<Costmap>(static_cast<int>(costs.shape(1)), static_cast<int>(costs.shape(0)),
                                                  resolution, origin);
             std::copy(costs.data(), costs.data() + costs.size(), map->costs().begin());
             return map;
           }),
           py::arg("costs"), py::arg("resolution"), py::arg("origin"))
      .def_property_readonly("width", &Costmap::width)
      .def_property_readonly("height", &Costmap::height)
      .def_property_readonly("resolution", &Costmap::resolution)
      .def_property_readonly("origin", [](const Costmap& c) { return Eigen::Vector2d(c.origin()); })
      .def("costs", [](const Costmap& c) {
        py::array_t<uint8_t> out({c.height(), c.width()});
        std::copy(c.costs().begin(), c.costs().end(), out.mutable_data());
        return out;
      })
      .def("set_costs",
           [](Costmap& c, const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& costs) {
             if (costs.ndim() != 2 || costs.shape(0) != c.height() || costs.shape(1) != c.width()) {
               throw std::invalid_argument("set_costs: the array must be height x width = " + std::to_string(c.height()) +
                                           " x " + std::to_string(c.width()));
             }
             std::copy(costs.data(), costs.data() + costs.size(), c.costs().begin());
           })
      .def("move_origin", &Costmap::moveOrigin, py::arg("new_origin"), py::arg("fill"))
      .def(
          "inflate",
          [](Costmap& c, double inscribed_radius, double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
            mbot::core::InflationParams p{inscribed_radius, inflation_radius, cost_scaling_factor, inflate_unknown};
            py::gil_scoped_release release;
            mbot::core::inflate(c, p);
          },
          "Inflates this costmap in place (no copies: as a node does).", py::arg("inscribed_radius"),
          py::arg("inflation_radius"), py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false)
      .def(
          "inflate_window",
          [](Costmap& c, const Costmap& base, int x0, int y0, int x1, int y1, double inscribed_radius,
             double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
            mbot::core::InflationParams p{inscribed_radius, inflation_radius, cost_scaling_factor, inflate_unknown};
            py::gil_scoped_release release;
            mbot::core::inflateWindow(base, c, {x0, y0, x1, y1}, p);
          },
          "Cells [x0, x1) x [y0, y1) become base's, inflated (bounded update).", py::arg("base"), py::arg("x0"),
          py::arg("y0"), py::arg("x1"), py::arg("y1"), py::arg("inscribed_radius"), py::arg("inflation_radius"),
          py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false)
      .def(
          "update_with_scan",
          [](Costmap& c, const Eigen::Vector3d& sensor_pose, double angle_min, double angle_increment, double range_min,
             double range_max, const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges,
             double obstacle_range, double raytrace_range, bool marking, bool clearing, bool inf_is_valid,
             bool too_close_is_obstacle, double raytrace_end_margin) {
            mbot::core::ObservationSourceParams p;
            p.raytrace_end_margin = raytrace_end_margin;
            p.obstacle_range = obstacle_range;
            p.raytrace_range = raytrace_range;
            p.marking = marking;
            p.clearing = clearing;
            p.inf_is_valid = inf_is_valid;
            p.too_close_is_obstacle = too_close_is_obstacle;
            const LaserScan scan = toScan(angle_min, angle_increment, range_min, range_max, ranges);
            py::gil_scoped_release release;
            return mbot::core::updateWithScan(c, sensor_pose, scan, p);
          },
          py::arg("sensor_pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"),
          py::arg("range_max"), py::arg("ranges"), py::arg("obstacle_range"), py::arg("raytrace_range"),
          py::arg("marking") = true, py::arg("clearing") = true, py::arg("inf_is_valid") = true,
          py::arg("too_close_is_obstacle") = true,
          py::arg("raytrace_end_margin") = mbot::core::ObservationSourceParams().raytrace_end_margin)
      .def(
          "footprint_cost",
          [](const Costmap& c, const Eigen::Vector3d& pose, const std::vector<Eigen::Vector2d>& footprint,
             bool unknown_is_obstacle) { return mbot::core::footprintCost(c, pose, footprint, unknown_is_obstacle); },
          py::arg("pose"), py::arg("footprint"), py::arg("unknown_is_obstacle") = true)
      .def(
          "footprint_cells",
          [](const Costmap& c, const Eigen::Vector3d& pose, const std::vector<Eigen::Vector2d>& footprint) {
            std::vector<std::pair<int, int>> out;
            for (const auto& cell : mbot::core::footprintCells(c, pose, footprint)) out.emplace_back(cell.x, cell.y);
            return out;
          },
          py::arg("pose"), py::arg("footprint"))
      .def("occupancy_data", [](const Costmap& c) {
        const auto d = c.toOccupancyData();
        py::array_t<int8_t> out({c.height(), c.width()});
        std::copy(d.begin(), d.end(), out.mutable_data());
        return out;
      });
  using mbot::core::GlobalPlanner;
  py::class_<GlobalPlanner>(m, "_GlobalPlanner")
      .def(py::init([](bool use_astar, bool allow_unknown, double default_tolerance, bool use_bounds) {
             mbot::core::PlannerParams p;
             p.use_astar = use_astar;
             p.allow_unknown = allow_unknown;
             p.default_tolerance = default_tolerance;
             p.use_bounds = use_bounds;
             return std::make_unique<GlobalPlanner>(p);
           }),
           py::arg("use_astar") = false, py::arg("allow_unknown") = true, py::arg("default_tolerance") = 0.0,
           py::arg("use_bounds") = true)
      .def(
          "make_plan",
          [](GlobalPlanner& planner, const Costmap& map, const Eigen::Vector2d& start, const Eigen::Vector2d& goal) {
            mbot::core::Plan plan;
            {
              py::gil_scoped_release release;
              plan = planner.makePlan(map, start, goal);
            }
            py::array_t<double> path({static_cast<py::ssize_t>(plan.path.size()), static_cast<py::ssize_t>(2)});
            auto out = path.mutable_unchecked<2>();
            for (std::size_t i = 0; i < plan.path.size(); ++i) {
              out(i, 0) = plan.path[i].x();
              out(i, 1) = plan.path[i].y();
            }
            return py::make_tuple(std::string(mbot::core::toString(plan.status)), path, plan.message, plan.expanded,
                                  plan.coarse_blocks);
          },
          py::arg("costmap"), py::arg("start"), py::arg("goal"))
      .def(
          "potential",
          [](const GlobalPlanner& planner, const Costmap& map) {
            py::array_t<float> out({map.height(), map.width()});
            float* d = out.mutable_data();
            for (std::size_t i = 0; i < map.costs().size(); ++i) d[i] = planner.valueAt(i);
            return out;
          },
          py::arg("costmap"));

  // The explorer's path lengths over a passable grid and its tour through the goals.
  m.def(
      "_path_lengths",
      [](py::array_t<uint8_t, py::array::c_style | py::array::forcecast> passable, int col, int row) {
        if (passable.ndim() != 2) throw std::invalid_argument("_path_lengths: passable must be a 2D array");
        const int h = static_cast<int>(passable.shape(0)), w = static_cast<int>(passable.shape(1));
        std::vector<uint8_t> cells(passable.data(), passable.data() + passable.size());
        std::vector<float> d;
        {
          py::gil_scoped_release release;
          d = mbot::core::pathLengths(cells, w, h, mbot::core::Cell{col, row});
        }
        py::array_t<float> out({h, w});
        std::copy(d.begin(), d.end(), out.mutable_data());
        return out;
      },
      py::arg("passable"), py::arg("col"), py::arg("row"));
  m.def(
      "_path_lengths_between",
      [](py::array_t<uint8_t, py::array::c_style | py::array::forcecast> passable,
         py::array_t<int, py::array::c_style | py::array::forcecast> rows,
         py::array_t<int, py::array::c_style | py::array::forcecast> cols) {
        if (passable.ndim() != 2) throw std::invalid_argument("_path_lengths_between: passable must be a 2D array");
        if (rows.ndim() != 1 || cols.ndim() != 1 || rows.size() != cols.size()) {
          throw std::invalid_argument("_path_lengths_between: rows and cols must be 1D arrays of one length");
        }
        const int h = static_cast<int>(passable.shape(0)), w = static_cast<int>(passable.shape(1));
        std::vector<uint8_t> grid(passable.data(), passable.data() + passable.size());
        std::vector<mbot::core::Cell> cells;
        for (py::ssize_t i = 0; i < rows.size(); ++i) cells.push_back(mbot::core::Cell{cols.at(i), rows.at(i)});
        std::vector<double> d;
        {
          py::gil_scoped_release release;
          d = mbot::core::pathLengthsBetween(grid, w, h, cells);
        }
        const py::ssize_t n = static_cast<py::ssize_t>(cells.size());
        py::array_t<double> out({n, n});
        std::copy(d.begin(), d.end(), out.mutable_data());
        return out;
      },
      py::arg("passable"), py::arg("rows"), py::arg("cols"));
  m.def(
      "_shortest_paths_through_all",
      [](py::array_t<double, py::array::c_style | py::array::forcecast> d, int exact_max) {
        if (d.ndim() != 2 || d.shape(0) != d.shape(1)) {
          throw std::invalid_argument("_shortest_paths_through_all: d must be an n x n array");
        }
        const int n = static_cast<int>(d.shape(0));
        std::vector<double> m(d.data(), d.data() + d.size());
        std::vector<double> rest;
        {
          py::gil_scoped_release release;
          rest = mbot::core::shortestPathsThroughAll(m, n, exact_max);
        }
        return py::array_t<double>(n, rest.data());
      },
      py::arg("d"), py::arg("exact_max") = 12);
}

}  // namespace bindings
}  // namespace mbot
