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

bool insidePolygon(const Eigen::Vector2d* corners, std::size_t n, const Eigen::Vector2d& q) {
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d &a = corners[i], &b = corners[j];
    if ((a.y() > q.y()) != (b.y() > q.y()) && q.x() < (b.x() - a.x()) * (q.y() - a.y()) / (b.y() - a.y()) + a.x()) inside = !inside;
  }
  return inside;
}

void validateFootprint(const Footprint& f) {
  if (f.size() < 3) throw std::invalid_argument("footprint needs at least 3 points, got " + std::to_string(f.size()));
  if (!insidePolygon(f.data(), f.size(), Eigen::Vector2d::Zero())) throw std::invalid_argument("footprint does not contain the robot's centre (0, 0)");
}

namespace {
/// Whether the segment a-b meets the rectangle (min x, min y, max x, max y) (Liang-Barsky clipping).
bool segmentMeetsRect(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector4d& box) {
  double t0 = 0.0, t1 = 1.0;
  const double d[2] = {b.x() - a.x(), b.y() - a.y()};
  const double lo[2] = {box[0] - a.x(), box[1] - a.y()}, hi[2] = {box[2] - a.x(), box[3] - a.y()};
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (lo[k] > 0.0 || hi[k] < 0.0) return false;
      continue;
    }
    double ta = lo[k] / d[k], tb = hi[k] / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}


/// A lethal cell's box in the grid's cell units, grown by cell_box::kMargin plus `extra` [m].
Eigen::Vector4d boxInCells(const Costmap& map, const Cell& c, double extra) {
  const Eigen::Vector4d b = map.obstacleBounds(c, cell_box::kMargin + extra);
  const double res = map.resolution(), ox = map.origin().x(), oy = map.origin().y();
  return {(b[0] - ox) / res, (b[1] - oy) / res, (b[2] - ox) / res, (b[3] - oy) / res};
}

/// The radius of a footprint whose vertices all lie on one circle about the centre and that has at
/// least 8 of them (robot_radius's 16-gon, padded or scaled), else 0.
double roundRadius(const Footprint& footprint) {
  if (footprint.size() < 8) return 0.0;
  const double r2 = footprint[0].squaredNorm();
  for (const auto& v : footprint) {
    if (std::abs(v.squaredNorm() - r2) > 1e-9 * r2) return 0.0;
  }
  return std::sqrt(r2);
}

/// footprintCost of a round robot: every cell the circle of `radius` about (x, y) passes through,
/// so that turning on the spot never changes the answer (the 16-gon's outline cells do change as
/// it turns: a robot at its goal could not turn to the goal's yaw beside a wall corner).
int ringCost(const Costmap& map, double x, double y, double radius, bool unknown_is_obstacle, double box_margin) {
  const double res = map.resolution();
  const double cx = (x - map.origin().x()) / res, cy = (y - map.origin().y()) / res, r = radius / res, r2 = r * r;
  const int x_lo = static_cast<int>(std::floor(cx - r)), x_hi = static_cast<int>(std::floor(cx + r));
  const int y_lo = static_cast<int>(std::floor(cy - r)), y_hi = static_cast<int>(std::floor(cy + r));
  if (x_lo < 0 || y_lo < 0 || x_hi >= map.width() || y_hi >= map.height()) return -1;
  const uint8_t* costs = map.costs().data();
  const int w = map.width();
  int worst = 0;
  for (int j = y_lo; j <= y_hi; ++j) {
    // Row j spans [j, j + 1): the cells it shares with the disc, minus those wholly inside it.
    const double near_y = cy < j ? j - cy : (cy > j + 1 ? cy - (j + 1) : 0.0);
    const double far_y = std::max(std::abs(cy - j), std::abs(cy - (j + 1)));
    const double a = std::sqrt(std::max(0.0, r2 - near_y * near_y));
    const int out_lo = std::max(x_lo, static_cast<int>(std::floor(cx - a))), out_hi = std::min(x_hi, static_cast<int>(std::floor(cx + a)));
    int in_lo = out_hi + 1, in_hi = out_hi;  // empty unless the row's far edge is inside the circle
    if (far_y < r) {
      const double b = std::sqrt(r2 - far_y * far_y);
      in_lo = static_cast<int>(std::ceil(cx - b));
      in_hi = static_cast<int>(std::floor(cx + b)) - 1;
    }
    const uint8_t* row = costs + static_cast<std::size_t>(j) * w;
    for (int i = out_lo; i <= out_hi; ++i) {
      if (i >= in_lo && i <= in_hi) {
        i = in_hi;
        continue;
      }
      const uint8_t v = row[i];
      if (v == cost::kLethal && map.box(static_cast<std::size_t>(j) * w + i) != cell_box::kNoBox) {
        // The obstacle's box, not the whole cell: touched when nearer to the centre than r.
        if (cell_box::squaredDistance(boxInCells(map, {i, j}, box_margin), cx, cy) < r2) return -1;
        worst = std::max(worst, static_cast<int>(cost::kInscribed));
        continue;
      }
      if (v == cost::kLethal || (v == cost::kNoInformation && unknown_is_obstacle)) return -1;
      if (v != cost::kNoInformation) worst = std::max(worst, static_cast<int>(v));
    }
  }
  return worst;
}
}  // namespace

bool footprintMeetsRect(const Eigen::Vector3d& pose, const Footprint& footprint, const Eigen::Vector4d& rect) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  std::vector<Eigen::Vector2d> corners;
  for (const auto& v : footprint) corners.emplace_back(pose.x() + c * v.x() - s * v.y(), pose.y() + s * v.x() + c * v.y());
  for (std::size_t i = 0, j = corners.size() - 1; i < corners.size(); j = i++) {
    if (segmentMeetsRect(corners[j], corners[i], rect)) return true;
  }
  return insidePolygon(corners.data(), corners.size(), {0.5 * (rect[0] + rect[2]), 0.5 * (rect[1] + rect[3])});
}

double contactRadius(const Footprint& footprint) {
  const double round = roundRadius(footprint);
  return round > 0.0 ? round : inscribedRadius(footprint);
}

int footprintCost(const Costmap& map, const Eigen::Vector3d& pose, const Footprint& footprint, bool unknown_is_obstacle,
                  double box_margin) {
  const double round = roundRadius(footprint);
  if (round > 0.0) return ringCost(map, pose.x(), pose.y(), round, unknown_is_obstacle, box_margin);
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  // The local planner calls this for every step of every trajectory: corners in a stack array when
  // they fit (no allocation, no thread-local lookup). Corners in cell units; cells by flooring, as
  // Costmap::worldToCell: a multiplication by 1 / resolution puts points on cell borders into the
  // other cell.
  constexpr std::size_t kStack = 32;
  Eigen::Vector2d stack_corners[kStack];
  thread_local std::vector<Eigen::Vector2d> heap_corners;
  Eigen::Vector2d* corners = stack_corners;
  if (footprint.size() > kStack) {
    heap_corners.resize(footprint.size());
    corners = heap_corners.data();
  }
  const double res = map.resolution(), ox = map.origin().x(), oy = map.origin().y();
  Cell lo{std::numeric_limits<int>::max(), std::numeric_limits<int>::max()}, hi{std::numeric_limits<int>::min(), std::numeric_limits<int>::min()};
  const std::size_t n = footprint.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& v = footprint[i];
    corners[i] = {(pose.x() + c * v.x() - s * v.y() - ox) / res, (pose.y() + s * v.x() + c * v.y() - oy) / res};
    const Cell cell{static_cast<int>(std::floor(corners[i].x())), static_cast<int>(std::floor(corners[i].y()))};
    lo = {std::min(lo.x, cell.x), std::min(lo.y, cell.y)};
    hi = {std::max(hi.x, cell.x), std::max(hi.y, cell.y)};
  }
  // Every outline cell lies between the corners' cells: inside the map if they all are.
  if (lo.x < 0 || lo.y < 0 || hi.x >= map.width() || hi.y >= map.height()) return -1;
  const uint8_t* costs = map.costs().data();
  const int w = map.width();
  int worst = 0;
  bool blocked = false;
  const bool boxes = map.hasBoxes();
  // Every cell the outline passes through (walkSegment), not Bresenham's cells between the corner
  // cells: those let a wall corner 2 cm inside the outline go unseen (the mbot wedged itself so
  // against the home's kitchen door jamb).
  for (std::size_t i = 0, j = n - 1; i < n && !blocked; j = i++) {
    // Each edge starts where the last one ended: that corner cell is visited once, by the first
    // (but for a box, which each edge must be checked against).
    bool first = j != n - 1;
    walkSegment(corners[j].x(), corners[j].y(), corners[i].x(), corners[i].y(), [&](const Cell& cell) {
      const std::size_t k = static_cast<std::size_t>(cell.y) * w + cell.x;
      const uint8_t v = costs[k];
      if (first) {
        first = false;
        if (!(v == cost::kLethal && boxes && map.box(k) != cell_box::kNoBox)) return true;
      }
      if (v == cost::kLethal && boxes && map.box(k) != cell_box::kNoBox) {
        // The obstacle's box, not the whole cell: touched when this edge or the inside meets it.
        const Eigen::Vector4d b = boxInCells(map, cell, box_margin);
        if (segmentMeetsRect(corners[j], corners[i], b) ||
            insidePolygon(corners, n, {0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])})) {
          blocked = true;
          return false;
        }
        worst = std::max(worst, static_cast<int>(cost::kInscribed));
        return true;
      }
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
