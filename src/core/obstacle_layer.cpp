#include "mbot_slam_navigation/core/obstacle_layer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {

void ObservationSourceParams::validate() const {
  if (!(obstacle_range > 0.0)) throw std::invalid_argument("obstacle_range must be positive");
  if (!(raytrace_range > 0.0)) throw std::invalid_argument("raytrace_range must be positive");
}

int updateWithScan(Costmap& layer, const Eigen::Vector3d& sensor_pose, const LaserScan& scan,
                   const ObservationSourceParams& params, std::vector<Cell>* too_close) {
  params.validate();
  const Eigen::Vector2d origin = sensor_pose.head<2>();
  const Cell from = layer.worldToCell(origin);
  struct Mark {
    Cell cell;
    Eigen::Vector2d at;  // [cells] the return in the grid's cell units; NaN: the whole cell
  };
  std::vector<Mark> marks;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    double r = scan.ranges_m[i];
    bool is_return = true;
    if (std::isinf(r) && r < 0.0) {
      // REP 117: something nearer than range_min. Nothing to clear; its place is known to within
      // range_min, so it is marked there (inside the footprint: the robot must not drive into it).
      if (!params.too_close_is_obstacle || !params.marking) continue;
      const double a = sensor_pose.z() + scan.beamAngle(i);
      const Cell end = layer.worldToCell(origin + scan.range_min_m * Eigen::Vector2d(std::cos(a), std::sin(a)));
      if (layer.contains(end)) {
        marks.push_back({end, {nan, nan}});
        if (too_close) too_close->push_back(end);
      }
      continue;
    }
    if (std::isnan(r) || r < scan.range_min_m) continue;  // NaN, or a driver's finite error code: nothing known
    if (std::isinf(r) || r >= scan.range_max_m) {
      if (!params.inf_is_valid) continue;
      r = std::min(params.raytrace_range, scan.range_max_m);
      is_return = false;
    }
    const double a = sensor_pose.z() + scan.beamAngle(i);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    const Cell end = layer.worldToCell(origin + r * dir);
    if (params.clearing) {
      const double clear_r = std::min(r, params.raytrace_range);
      const Cell clear_end = layer.worldToCell(origin + clear_r * dir);
      // Clear up to the end point's cell, never the end point itself (it is what the beam hit).
      // A whole cell, box or not: a beam that misses a small box is no proof the obstacle stayed,
      // and a person's marks must go when the person does (docs/experiments.md).
      walkLine(from, clear_end, [&](const Cell& c) {
        if (!layer.contains(c)) return false;
        if (is_return && c == end) return false;
        layer.setCost(c, cost::kFree);
        return true;
      });
    }
    if (params.marking && is_return && r < params.obstacle_range && layer.contains(end)) {
      marks.push_back({end, (origin + r * dir - layer.origin()) / layer.resolution()});
    }
  }
  // After clearing, as costmap_2d. A cell lethal before (and not cleared since) grows its box.
  for (const Mark& m : marks) {
    const std::size_t i = layer.index(m.cell);
    const bool fresh = layer.cost(m.cell) != cost::kLethal;
    layer.setCost(m.cell, cost::kLethal);
    if (std::isnan(m.at.x())) {
      layer.setBox(i, cell_box::kNoBox);
    } else {
      const double fx = m.at.x() - m.cell.x, fy = m.at.y() - m.cell.y;
      layer.setBox(i, fresh ? cell_box::ofPoint(fx, fy) : cell_box::grow(layer.box(i), fx, fy));
    }
  }
  return static_cast<int>(marks.size());
}

}  // namespace core
}  // namespace mbot
