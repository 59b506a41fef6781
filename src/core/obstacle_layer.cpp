#include "mbot_slam_navigation/core/obstacle_layer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {

void ObservationSourceParams::validate() const {
  if (!(obstacle_range > 0.0)) throw std::invalid_argument("obstacle_range must be positive");
  if (!(raytrace_range > 0.0)) throw std::invalid_argument("raytrace_range must be positive");
}

namespace {
/// [m] Neighbouring returns this close in range lie on one surface (for the median of three).
constexpr double kSameSurface_m = 0.05;
}  // namespace

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
      // A return clears the cells the beam leaves more than raytrace_end_margin short of its end,
      // never the end point's cell (it is what the beam hit): the returns off one surface scatter
      // by the laser's noise, and a beam ending just past a cell border must not erase the cell
      // in front of it that the previous scan's returns marked (the surface would flicker between
      // the two cells, a gap one cell wider and narrower from scan to scan).
      // (With a margin of 0 the cell the beam stops short in is the end point's: costmap_2d's rule.)
      const double short_r = is_return ? r - params.raytrace_end_margin : r;
      const bool stop_short = is_return && short_r < params.raytrace_range;
      const double clear_r = std::min(short_r, params.raytrace_range);
      // A whole cell, box or not: a beam that misses a small box is no proof the obstacle stayed,
      // and a person's marks must go when the person does (docs/experiments.md).
      if (clear_r > 0.0) {
        const Cell clear_end = layer.worldToCell(origin + clear_r * dir);
        walkLine(from, clear_end, [&](const Cell& c) {
          if (!layer.contains(c)) return false;
          if (is_return && (c == end || (stop_short && c == clear_end))) return false;
          layer.setCost(c, cost::kFree);
          return true;
        });
      }
    }
    if (params.marking && is_return && r < params.obstacle_range && layer.contains(end)) {
      // A box is placed by the median of the beam's and its neighbours' ranges where the three
      // lie on one surface: the laser's noise, which would spread the box towards the robot,
      // shrinks to about two thirds, and a point off a surface's edge keeps its own range.
      double at_r = r;
      if (layer.hasBoxes() && i > 0 && i + 1 < scan.ranges_m.size()) {
        const double a0 = scan.ranges_m[i - 1], a2 = scan.ranges_m[i + 1];
        if (std::isfinite(a0) && std::isfinite(a2) && std::abs(a0 - r) <= kSameSurface_m &&
            std::abs(a2 - r) <= kSameSurface_m) {
          at_r = std::max(std::min(a0, a2), std::min(std::max(a0, a2), r));
        }
      }
      const Cell at_cell = layer.worldToCell(origin + at_r * dir);
      if (layer.contains(at_cell)) marks.push_back({at_cell, (origin + at_r * dir - layer.origin()) / layer.resolution()});
    }
  }
  // After clearing, as costmap_2d. A marked cell's box is that of this scan's returns in it: the
  // returns off a surface scatter by the laser's noise towards the robot and away, and a box
  // grown by every scan's would reach out by the largest deviation of hundreds (2.5 standard
  // deviations), enough to shut a gap that leaves the robot 2-3 cm a side.
  std::unordered_set<std::size_t> boxed;  // cells given a box by this scan
  for (const Mark& m : marks) {
    const std::size_t i = layer.index(m.cell);
    layer.setCost(m.cell, cost::kLethal);
    if (std::isnan(m.at.x())) {
      layer.setBox(i, cell_box::kNoBox);
      boxed.insert(i);  // a whole cell, whatever else this scan saw in it
    } else {
      const double fx = m.at.x() - m.cell.x, fy = m.at.y() - m.cell.y;
      layer.setBox(i, boxed.insert(i).second ? cell_box::ofPoint(fx, fy) : cell_box::grow(layer.box(i), fx, fy));
    }
  }
  return static_cast<int>(marks.size());
}

}  // namespace core
}  // namespace mbot
