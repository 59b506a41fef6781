#include "mbot_slam_navigation/core/world2d.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace mbot {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Ray p + t d (|d| = 1) against segment a-b: t >= 0 of the crossing, or +inf.
double raySegment(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Eigen::Vector2d& a,
                  const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a;
  const double denom = cross(d, e);
  if (std::abs(denom) < 1e-15) return kInf;  // parallel: grazing contact is not a return
  const Eigen::Vector2d ap = a - p;
  const double t = cross(ap, e) / denom;
  const double s = cross(ap, d) / denom;
  return (t >= 0.0 && s >= 0.0 && s <= 1.0) ? t : kInf;
}

double rayCircle(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Eigen::Vector2d& c, double r) {
  const Eigen::Vector2d m = p - c;
  const double b = m.dot(d);
  const double cc = m.squaredNorm() - r * r;
  if (cc <= 0.0) return 0.0;  // starts inside
  const double disc = b * b - cc;
  if (disc < 0.0 || b > 0.0) return kInf;
  return -b - std::sqrt(disc);
}

bool segmentsIntersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                       const Eigen::Vector2d& q2) {
  const double d1 = cross(q2 - q1, p1 - q1), d2 = cross(q2 - q1, p2 - q1);
  const double d3 = cross(p2 - p1, q1 - p1), d4 = cross(p2 - p1, q2 - p1);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto onSegment = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& q) {
    return q.x() >= std::min(a.x(), b.x()) - 1e-12 && q.x() <= std::max(a.x(), b.x()) + 1e-12 &&
           q.y() >= std::min(a.y(), b.y()) - 1e-12 && q.y() <= std::max(a.y(), b.y()) + 1e-12;
  };
  return (d1 == 0 && onSegment(q1, q2, p1)) || (d2 == 0 && onSegment(q1, q2, p2)) ||
         (d3 == 0 && onSegment(p1, p2, q1)) || (d4 == 0 && onSegment(p1, p2, q2));
}

bool pointInPolygon(const Eigen::Vector2d& q, const Polygon& poly) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[j];
    if ((a.y() > q.y()) != (b.y() > q.y()) && q.x() < (b.x() - a.x()) * (q.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

double pointSegmentDistance(const Eigen::Vector2d& q, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a;
  const double len2 = e.squaredNorm();
  const double t = len2 > 0 ? std::clamp((q - a).dot(e) / len2, 0.0, 1.0) : 0.0;
  return (a + t * e - q).norm();
}

bool polygonsOverlap(const Polygon& p, const Polygon& q) {
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
    for (std::size_t k = 0, l = q.size() - 1; k < q.size(); l = k++) {
      if (segmentsIntersect(p[j], p[i], q[l], q[k])) return true;
    }
  }
  return pointInPolygon(p[0], q) || pointInPolygon(q[0], p);
}

double rayPolygon(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Polygon& poly) {
  double best = kInf;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) best = std::min(best, raySegment(p, d, poly[j], poly[i]));
  return best;
}

bool polygonTouchesCircle(const Polygon& polygon, const Eigen::Vector2d& c, double r) {
  if (pointInPolygon(c, polygon)) return true;
  for (std::size_t a = 0, b = polygon.size() - 1; a < polygon.size(); b = a++) {
    if (pointSegmentDistance(c, polygon[b], polygon[a]) < r) return true;
  }
  return false;
}

// Ray p + t d (|d| = 1, world frame) against a raster: t >= 0 where the ray enters the first solid
// cell (0 if it starts in one), or +inf within [0, t_max]. Walks the cells (Amanatides & Woo) in
// the raster's own frame.
double rayGrid(const Eigen::Vector2d& p_world, const Eigen::Vector2d& d_world, const GridShape& g, double t_max) {
  const double c = std::cos(g.yaw), s = std::sin(g.yaw);
  const Eigen::Vector2d q = p_world - g.origin;
  const Eigen::Vector2d p((c * q.x() + s * q.y()) / g.resolution, (-s * q.x() + c * q.y()) / g.resolution);  // in cells
  const Eigen::Vector2d d(c * d_world.x() + s * d_world.y(), -s * d_world.x() + c * d_world.y());
  const double size[2] = {static_cast<double>(g.width), static_cast<double>(g.height)};
  double t0 = 0.0, t1 = t_max / g.resolution;  // in cells along the ray
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (p[k] < 0.0 || p[k] > size[k]) return kInf;
    } else {
      double ta = (0.0 - p[k]) / d[k], tb = (size[k] - p[k]) / d[k];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
  }
  if (t0 > t1) return kInf;
  const Eigen::Vector2d start = p + t0 * d;
  int x = std::clamp(static_cast<int>(std::floor(start.x())), 0, g.width - 1);
  int y = std::clamp(static_cast<int>(std::floor(start.y())), 0, g.height - 1);
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  const double dt_x = std::abs(d.x()) > 1e-15 ? 1.0 / std::abs(d.x()) : kInf;
  const double dt_y = std::abs(d.y()) > 1e-15 ? 1.0 / std::abs(d.y()) : kInf;
  double next_x = std::abs(d.x()) > 1e-15 ? (x + (step_x > 0 ? 1 : 0) - p.x()) / d.x() : kInf;
  double next_y = std::abs(d.y()) > 1e-15 ? (y + (step_y > 0 ? 1 : 0) - p.y()) / d.y() : kInf;
  double entered = t0;
  while (true) {
    if (g.solid(x, y)) return entered * g.resolution;
    entered = std::min(next_x, next_y);
    if (entered > t1) return kInf;
    if (next_x < next_y) {
      x += step_x;
      next_x += dt_x;
      if (x < 0 || x >= g.width) return kInf;
    } else {
      y += step_y;
      next_y += dt_y;
      if (y < 0 || y >= g.height) return kInf;
    }
  }
}

// True if the polygon (world frame) touches a solid cell of the raster.
bool polygonTouchesGrid(const Polygon& polygon_world, const GridShape& g) {
  const double c = std::cos(g.yaw), s = std::sin(g.yaw);
  Polygon local;
  local.reserve(polygon_world.size());
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(kInf), hi = Eigen::Vector2d::Constant(-kInf);
  for (const auto& v : polygon_world) {
    const Eigen::Vector2d q = v - g.origin;
    local.emplace_back((c * q.x() + s * q.y()) / g.resolution, (-s * q.x() + c * q.y()) / g.resolution);
    lo = lo.cwiseMin(local.back());
    hi = hi.cwiseMax(local.back());
  }
  const int x0 = std::max(0, static_cast<int>(std::floor(lo.x()))), x1 = std::min(g.width - 1, static_cast<int>(std::floor(hi.x())));
  const int y0 = std::max(0, static_cast<int>(std::floor(lo.y()))), y1 = std::min(g.height - 1, static_cast<int>(std::floor(hi.y())));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (!g.solid(x, y)) continue;
      const Polygon cell = {{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}};
      if (polygonsOverlap(local, cell)) return true;
    }
  }
  return false;
}

}  // namespace

double pointPolygonDistance(const Eigen::Vector2d& point, const Polygon& polygon) {
  if (polygon.empty()) return kInf;
  if (polygon.size() >= 3 && pointInPolygon(point, polygon)) return 0.0;
  double best = kInf;
  for (std::size_t a = 0, b = polygon.size() - 1; a < polygon.size(); b = a++) {
    best = std::min(best, pointSegmentDistance(point, polygon[b], polygon[a]));
  }
  return best;
}

double World2D::distanceToDynamicPolygons(const Eigen::Vector2d& point) const {
  double best = kInf;
  for (const Polygon& p : dynamic_) best = std::min(best, pointPolygonDistance(point, p));
  return best;
}

World2D::World2D(double bucket_size_m) : bucket_(bucket_size_m) {
  if (!(bucket_size_m > 0.0)) throw std::invalid_argument("World2D: bucket size must be positive");
}

void World2D::addSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, HeightRange heights) {
  segments_.push_back({a, b, heights});
  dirty_ = true;
}

void World2D::addPolygon(const Polygon& polygon, HeightRange heights) {
  if (polygon.size() < 3) throw std::invalid_argument("World2D: a polygon needs at least 3 vertices");
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) addSegment(polygon[j], polygon[i], heights);
  solids_.push_back({polygon, heights});
}

void World2D::addGrid(GridShape grid) {
  if (grid.width <= 0 || grid.height <= 0 || grid.cells.size() != static_cast<std::size_t>(grid.width) * grid.height) {
    throw std::invalid_argument("World2D: a grid of " + std::to_string(grid.width) + " x " + std::to_string(grid.height) +
                                " cells needs as many values, got " + std::to_string(grid.cells.size()));
  }
  if (!(grid.resolution > 0.0)) throw std::invalid_argument("World2D: a grid's resolution must be positive");
  grids_.push_back(std::move(grid));
}

void World2D::addBox(const Eigen::Vector2d& center, double yaw_rad, double size_x_m, double size_y_m,
                     HeightRange heights) {
  if (!(size_x_m > 0.0 && size_y_m > 0.0)) throw std::invalid_argument("World2D: box sizes must be positive");
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  Polygon box;
  for (const auto& k : {Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1), Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)}) {
    const Eigen::Vector2d local(0.5 * size_x_m * k.x(), 0.5 * size_y_m * k.y());
    box.push_back(center + Eigen::Vector2d(c * local.x() - s * local.y(), s * local.x() + c * local.y()));
  }
  addPolygon(box, heights);
}

void World2D::addCylinder(const Eigen::Vector2d& center, double radius_m, HeightRange heights) {
  if (!(radius_m > 0.0)) throw std::invalid_argument("World2D: cylinder radius must be positive");
  circles_.push_back({center, radius_m, heights});
  dirty_ = true;
}

void World2D::bucketRange(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, int& x0, int& y0, int& x1,
                          int& y1) const {
  x0 = std::clamp(static_cast<int>(std::floor((lo.x() - lo_.x()) / bucket_)), 0, nx_ - 1);
  y0 = std::clamp(static_cast<int>(std::floor((lo.y() - lo_.y()) / bucket_)), 0, ny_ - 1);
  x1 = std::clamp(static_cast<int>(std::floor((hi.x() - lo_.x()) / bucket_)), 0, nx_ - 1);
  y1 = std::clamp(static_cast<int>(std::floor((hi.y() - lo_.y()) / bucket_)), 0, ny_ - 1);
}

void World2D::rebuildIfNeeded() const {
  if (!dirty_) return;
  dirty_ = false;
  lo_ = Eigen::Vector2d::Constant(kInf);
  hi_ = Eigen::Vector2d::Constant(-kInf);
  for (const Segment& s : segments_) {
    lo_ = lo_.cwiseMin(s.a).cwiseMin(s.b);
    hi_ = hi_.cwiseMax(s.a).cwiseMax(s.b);
  }
  for (const Circle& c : circles_) {
    lo_ = lo_.cwiseMin(c.c - Eigen::Vector2d::Constant(c.r));
    hi_ = hi_.cwiseMax(c.c + Eigen::Vector2d::Constant(c.r));
  }
  if (segments_.empty() && circles_.empty()) {
    nx_ = ny_ = 0;
    offsets_.assign(1, 0);
    items_.clear();
    return;
  }
  lo_ -= Eigen::Vector2d::Constant(1e-6);
  hi_ += Eigen::Vector2d::Constant(1e-6);
  nx_ = std::max(1, static_cast<int>(std::ceil((hi_.x() - lo_.x()) / bucket_)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi_.y() - lo_.y()) / bucket_)));
  std::vector<std::vector<int>> buckets(static_cast<std::size_t>(nx_) * ny_);
  auto insert = [&](const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, int item) {
    int x0, y0, x1, y1;
    bucketRange(lo, hi, x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) buckets[static_cast<std::size_t>(y) * nx_ + x].push_back(item);
  };
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    insert(segments_[i].a.cwiseMin(segments_[i].b), segments_[i].a.cwiseMax(segments_[i].b), static_cast<int>(i));
  }
  for (std::size_t i = 0; i < circles_.size(); ++i) {
    const Eigen::Vector2d r = Eigen::Vector2d::Constant(circles_[i].r);
    insert(circles_[i].c - r, circles_[i].c + r, -1 - static_cast<int>(i));
  }
  offsets_.assign(buckets.size() + 1, 0);
  items_.clear();
  for (std::size_t k = 0; k < buckets.size(); ++k) {
    items_.insert(items_.end(), buckets[k].begin(), buckets[k].end());
    offsets_[k + 1] = static_cast<int>(items_.size());
  }
}

double World2D::castRay(const Eigen::Vector2d& origin, double angle_rad, double max_range_m, int skip_dynamic,
                        double plane_z) const {
  rebuildIfNeeded();
  const Eigen::Vector2d d(std::cos(angle_rad), std::sin(angle_rad));
  double best = kInf;
  for (const GridShape& g : grids_) {
    if (g.heights.cuts(plane_z)) best = std::min(best, rayGrid(origin, d, g, std::min(best, max_range_m)));
  }
  for (std::size_t i = 0; i < dynamic_.size(); ++i) {
    if (static_cast<int>(i) != skip_dynamic) best = std::min(best, rayPolygon(origin, d, dynamic_[i]));
  }
  for (const Eigen::Vector3d& c : dynamic_circles_) best = std::min(best, rayCircle(origin, d, c.head<2>(), c.z()));
  if (nx_ > 0) {
    // Clip the ray to the grid's box (slab method).
    double t0 = 0.0, t1 = max_range_m;
    for (int k = 0; k < 2 && t0 <= t1; ++k) {
      if (std::abs(d[k]) < 1e-15) {
        if (origin[k] < lo_[k] || origin[k] > hi_[k]) t0 = kInf;
      } else {
        double ta = (lo_[k] - origin[k]) / d[k], tb = (hi_[k] - origin[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
    }
    if (t0 <= t1) {
      const Eigen::Vector2d start = origin + t0 * d;
      int x = std::clamp(static_cast<int>(std::floor((start.x() - lo_.x()) / bucket_)), 0, nx_ - 1);
      int y = std::clamp(static_cast<int>(std::floor((start.y() - lo_.y()) / bucket_)), 0, ny_ - 1);
      const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
      const double dt_x = std::abs(d.x()) > 1e-15 ? bucket_ / std::abs(d.x()) : kInf;
      const double dt_y = std::abs(d.y()) > 1e-15 ? bucket_ / std::abs(d.y()) : kInf;
      double next_x = std::abs(d.x()) > 1e-15
                          ? (lo_.x() + (x + (step_x > 0 ? 1 : 0)) * bucket_ - origin.x()) / d.x()
                          : kInf;
      double next_y = std::abs(d.y()) > 1e-15
                          ? (lo_.y() + (y + (step_y > 0 ? 1 : 0)) * bucket_ - origin.y()) / d.y()
                          : kInf;
      while (true) {
        const int k = y * nx_ + x;
        for (int j = offsets_[k]; j < offsets_[k + 1]; ++j) {
          const int item = items_[j];
          if (item >= 0) {
            const Segment& s = segments_[item];
            if (s.h.cuts(plane_z)) best = std::min(best, raySegment(origin, d, s.a, s.b));
          } else {
            const Circle& c = circles_[-1 - item];
            if (c.h.cuts(plane_z)) best = std::min(best, rayCircle(origin, d, c.c, c.r));
          }
        }
        const double exit = std::min(next_x, next_y);
        if (best <= exit || exit > t1) break;
        if (next_x < next_y) {
          x += step_x;
          next_x += dt_x;
          if (x < 0 || x >= nx_) break;
        } else {
          y += step_y;
          next_y += dt_y;
          if (y < 0 || y >= ny_) break;
        }
      }
    }
  }
  return best <= max_range_m ? best : kInf;
}

void World2D::castScan(const Eigen::Vector3d& sensor_pose, double angle_min_rad, double angle_increment_rad, int beams,
                       double range_min_m, double range_max_m, double noise_stddev_m, double range_resolution_m,
                       std::mt19937& rng, float* out, int skip_dynamic, double plane_z) const {
  std::normal_distribution<double> noise(0.0, noise_stddev_m > 0.0 ? noise_stddev_m : 1.0);
  const Eigen::Vector2d origin = sensor_pose.head<2>();
  for (int i = 0; i < beams; ++i) {
    double r = castRay(origin, sensor_pose.z() + angle_min_rad + i * angle_increment_rad, range_max_m, skip_dynamic, plane_z);
    if (std::isfinite(r)) {
      if (noise_stddev_m > 0.0) r += noise(rng);
      if (range_resolution_m > 0.0) r = std::round(r / range_resolution_m) * range_resolution_m;
      if (r >= range_max_m) r = kInf;
      else if (r < range_min_m) r = -kInf;
    }
    out[i] = static_cast<float>(r);
  }
}

bool World2D::overlaps(const Polygon& polygon, int skip_dynamic, HeightRange body) const {
  rebuildIfNeeded();
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(kInf), hi = Eigen::Vector2d::Constant(-kInf);
  for (const auto& v : polygon) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  for (std::size_t i = 0; i < dynamic_.size(); ++i) {
    if (static_cast<int>(i) != skip_dynamic && polygonsOverlap(polygon, dynamic_[i])) return true;
  }
  for (const Eigen::Vector3d& c : dynamic_circles_) {
    if (polygonTouchesCircle(polygon, c.head<2>(), c.z())) return true;
  }
  if (nx_ > 0) {
    int x0, y0, x1, y1;
    bucketRange(lo, hi, x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const int k = y * nx_ + x;
        for (int j = offsets_[k]; j < offsets_[k + 1]; ++j) {
          const int item = items_[j];
          if (item >= 0) {
            const Segment& s = segments_[item];
            if (!s.h.overlaps(body)) continue;
            if (pointInPolygon(s.a, polygon)) return true;
            for (std::size_t a = 0, b = polygon.size() - 1; a < polygon.size(); b = a++) {
              if (segmentsIntersect(polygon[b], polygon[a], s.a, s.b)) return true;
            }
          } else {
            const Circle& c = circles_[-1 - item];
            if (c.h.overlaps(body) && polygonTouchesCircle(polygon, c.c, c.r)) return true;
          }
        }
      }
    }
  }
  // Entirely inside a solid (no edge crossing): one vertex inside suffices.
  for (const Solid& s : solids_) {
    if (s.h.overlaps(body) && pointInPolygon(polygon[0], s.polygon)) return true;
  }
  for (const GridShape& g : grids_) {
    if (g.heights.overlaps(body) && polygonTouchesGrid(polygon, g)) return true;
  }
  return false;
}

}  // namespace core
}  // namespace mbot
