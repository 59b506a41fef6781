#include "mbot_slam_navigation/core/grid_raycast.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {
namespace {

// Distance along the unit direction d from p at which the ray enters the axis-aligned square
// [lo, hi] (slab method); 0 when p is already inside.
double entryDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Eigen::Vector2d& lo,
                     const Eigen::Vector2d& hi) {
  double t_enter = 0.0;
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-12) continue;
    const double t0 = (lo[k] - p[k]) / d[k];
    const double t1 = (hi[k] - p[k]) / d[k];
    t_enter = std::max(t_enter, std::min(t0, t1));
  }
  return t_enter;
}

}  // namespace

double castRay(const OccupancyGrid& grid, const Eigen::Vector2d& from, double angle_rad, double max_range_m,
               double occupied_probability) {
  const Eigen::Vector2d dir(std::cos(angle_rad), std::sin(angle_rad));
  const float threshold = probabilityToLogOdds(occupied_probability);
  double hit_range = std::numeric_limits<double>::infinity();
  walkLine(grid.worldToCell(from), grid.worldToCell(from + max_range_m * dir), [&](const Cell& c) {
    if (!grid.contains(c)) return false;
    if (grid.logOdds(c) > threshold) {
      const Eigen::Vector2d lo = grid.origin() + Eigen::Vector2d(c.x, c.y) * grid.resolution();
      const double r = entryDistance(from, dir, lo, lo + Eigen::Vector2d::Constant(grid.resolution()));
      if (r <= max_range_m) hit_range = r;
      return false;
    }
    return true;
  });
  return hit_range;
}

}  // namespace core
}  // namespace mbot
