#include "mbot_slam_navigation/core/footprint.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {

Footprint circleFootprint(double radius_m) {
  if (!(radius_m > 0.0)) throw std::invalid_argument("robot_radius must be positive");
  Footprint f;
  const int n = 16;
  const double r = radius_m / std::cos(M_PI / n);  // edges tangent to the circle
  for (int i = 0; i < n; ++i) f.emplace_back(r * std::cos(2 * M_PI * i / n), r * std::sin(2 * M_PI * i / n));
  return f;
}

Footprint padFootprint(const Footprint& footprint, double padding_m) {
  Footprint out;
  for (const auto& v : footprint) {
    const double n = v.norm();
    out.push_back(n > 0.0 ? Eigen::Vector2d(v * ((n + padding_m) / n)) : v);
  }
  return out;
}

double inscribedRadius(const Footprint& f) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = f.size() - 1; i < f.size(); j = i++) {
    const Eigen::Vector2d a = f[j], e = f[i] - f[j];
    const double t = e.squaredNorm() > 0 ? std::clamp(-a.dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * e).norm());
  }
  return best;
}

double circumscribedRadius(const Footprint& f) {
  double best = 0.0;
  for (const auto& v : f) best = std::max(best, v.norm());
  return best;
}

void validateFootprint(const Footprint& f) {
  if (f.size() < 3) throw std::invalid_argument("footprint needs at least 3 points, got " + std::to_string(f.size()));
  bool inside = false;  // even-odd test of the origin
  for (std::size_t i = 0, j = f.size() - 1; i < f.size(); j = i++) {
    if ((f[i].y() > 0) != (f[j].y() > 0) && 0 < (f[j].x() - f[i].x()) * (0 - f[i].y()) / (f[j].y() - f[i].y()) + f[i].x()) {
      inside = !inside;
    }
  }
  if (!inside) throw std::invalid_argument("footprint does not contain the robot's centre (0, 0)");
}

int footprintCost(const Costmap& map, const Eigen::Vector3d& pose, const Footprint& footprint, bool unknown_is_obstacle) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  // Reused between calls: the local planner calls this for every step of every trajectory.
  thread_local std::vector<Cell> corners;
  corners.clear();
  for (const auto& v : footprint) {
    corners.push_back(map.worldToCell({pose.x() + c * v.x() - s * v.y(), pose.y() + s * v.x() + c * v.y()}));
  }
  int worst = 0;
  bool blocked = false;
  for (std::size_t i = 0, j = corners.size() - 1; i < corners.size() && !blocked; j = i++) {
    walkLine(corners[j], corners[i], [&](const Cell& cell) {
      if (!map.contains(cell)) {
        blocked = true;
        return false;
      }
      const uint8_t v = map.cost(cell);
      if (v == cost::kLethal || (v == cost::kNoInformation && unknown_is_obstacle)) {
        blocked = true;
        return false;
      }
      if (v != cost::kNoInformation) worst = std::max(worst, static_cast<int>(v));
      return true;
    });
  }
  return blocked ? -1 : worst;
}

}  // namespace core
}  // namespace mbot
