// Shared by the binding files of the one pybind11 module `_core` (module.cpp): conversions at the
// boundary and one binding function per area. Bound names are private (leading underscore); the
// typed wrappers in src/mbot_slam_navigation/ are what Python code imports.
#pragma once

#include <utility>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "mbot_slam_navigation/core/cell.h"
#include "mbot_slam_navigation/core/laser_scan.h"

namespace mbot {
namespace bindings {

namespace py = pybind11;

inline core::Cell toCell(const std::pair<int, int>& c) { return core::Cell{c.first, c.second}; }

/// A laser scan from Python's numbers (ranges as float32, copied).
inline core::LaserScan toScan(double angle_min, double angle_increment, double range_min, double range_max,
                              const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges) {
  core::LaserScan scan;
  scan.angle_min_rad = angle_min;
  scan.angle_increment_rad = angle_increment;
  scan.range_min_m = range_min;
  scan.range_max_m = range_max;
  scan.ranges_m.assign(ranges.data(), ranges.data() + ranges.size());
  return scan;
}

/// Amcl's particle filter, and map_server's pixel rules for map images
void bindAmcl(py::module& m);
/// The log-odds occupancy grid, Bresenham lines and grid ray casting
void bindGrid(py::module& m);
/// The simulator's world (shapes, lasers) and its differential drive
void bindSimulation(py::module& m);
/// The SLAM backends and their parameters (offline tools and tests; the node is roscpp)
void bindSlam(py::module& m);
/// Costmaps, inflation, path lengths, tours and the global planner
void bindCostmaps(py::module& m);
/// Footprints and the local planner
void bindLocalPlanner(py::module& m);
/// Parameters, move_base's configuration, costmap layers and the local planner's settings
void bindNavigation(py::module& m);

}  // namespace bindings
}  // namespace mbot
