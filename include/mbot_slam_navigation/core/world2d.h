// The static 2D world of the simulator: line segments (walls, box sides) and circles (cylinders),
// with exact ray casting and footprint overlap tests.
//
// Ray casting walks a uniform grid of buckets (Amanatides & Woo, "A Fast Voxel Traversal Algorithm
// for Ray Tracing", Eurographics 1987): each bucket lists the shapes whose bounding box touches it,
// and the walk stops at the first bucket whose exit lies beyond the nearest hit found so far, so a
// ray costs the shapes near its path, not all shapes. All coordinates are in the world frame [m].
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

namespace mbot {
namespace core {

using Polygon = std::vector<Eigen::Vector2d>;  ///< vertices in order (either winding), closed implicitly

/// Distance [m] from `point` to the solid polygon: 0 inside it, else to its nearest side.
double pointPolygonDistance(const Eigen::Vector2d& point, const Polygon& polygon);

class World2D {
 public:
  /// Bucket edge length [m] of the ray-casting acceleration grid.
  explicit World2D(double bucket_size_m = 0.5);

  /// A box of size (sx, sy) [m] centred at `center` and rotated by yaw [rad].
  void addBox(const Eigen::Vector2d& center, double yaw_rad, double size_x_m, double size_y_m);
  /// A solid convex polygon (its sides become segments; containment counts for overlap tests).
  void addPolygon(const Polygon& polygon);
  void addCylinder(const Eigen::Vector2d& center, double radius_m);
  void addSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b);

  /// Moving obstacles (other robots' footprints), replaced wholesale each step; tested brute force.
  void setDynamicPolygons(const std::vector<Polygon>& polygons) { dynamic_ = polygons; }
  /// Moving round obstacles (people): each (x, y, radius) [m], replaced wholesale each step; seen by
  /// rays and by overlap tests like any shape, tested brute force.
  void setDynamicCircles(const std::vector<Eigen::Vector3d>& circles) { dynamic_circles_ = circles; }

  /// Distance [m] from `point` to the nearest dynamic polygon (0 inside one), +inf if there is none.
  double distanceToDynamicPolygons(const Eigen::Vector2d& point) const;

  /// Distance [m] from `origin` along `angle_rad` to the first surface, or +inf if none within
  /// `max_range_m`. Dynamic polygon `skip_dynamic` (the caster's own body) is ignored.
  double castRay(const Eigen::Vector2d& origin, double angle_rad, double max_range_m, int skip_dynamic = -1) const;

  /// A whole scan: beam i at yaw + angle_min + i * increment. Ranges follow REP 117: +inf for no
  /// return within range_max, -inf below range_min; gaussian noise of `noise_stddev_m` (if > 0)
  /// is added to returns, which are then quantized to `range_resolution_m` (if > 0).
  void castScan(const Eigen::Vector3d& sensor_pose, double angle_min_rad, double angle_increment_rad, int beams,
                double range_min_m, double range_max_m, double noise_stddev_m, double range_resolution_m,
                std::mt19937& rng, float* out, int skip_dynamic = -1) const;

  /// True if the solid polygon touches any static shape or dynamic polygon other than `skip_dynamic`.
  bool overlaps(const Polygon& polygon, int skip_dynamic = -1) const;

  int segmentCount() const { return static_cast<int>(segments_.size()); }
  int circleCount() const { return static_cast<int>(circles_.size()); }

 private:
  struct Segment {
    Eigen::Vector2d a, b;
  };
  struct Circle {
    Eigen::Vector2d c;
    double r;
  };
  void rebuildIfNeeded() const;
  void bucketRange(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, int& x0, int& y0, int& x1, int& y1) const;

  double bucket_;
  std::vector<Segment> segments_;
  std::vector<Circle> circles_;
  std::vector<Polygon> solids_;   // boxes and polygons, for containment tests
  std::vector<Polygon> dynamic_;
  std::vector<Eigen::Vector3d> dynamic_circles_;

  // Acceleration grid (CSR: for bucket k, items [offsets[k], offsets[k+1]) of `items`; an item >= 0
  // is a segment index, < 0 is circle index -1-item). Rebuilt lazily after shapes change.
  mutable bool dirty_ = true;
  mutable Eigen::Vector2d lo_, hi_;
  mutable int nx_ = 0, ny_ = 0;
  mutable std::vector<int> offsets_, items_;
};

}  // namespace core
}  // namespace mbot
