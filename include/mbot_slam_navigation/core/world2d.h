// The static 2D world of the simulator: line segments (walls, box sides), circles (cylinders) and
// occupancy rasters (floor plans, saved maps), with exact ray casting and footprint overlap tests.
//
// Every static shape spans a height range [z_lo, z_hi] [m above the floor]. A ray is cast in a
// horizontal plane at height z and sees only the shapes that plane cuts (a lintel above a door is
// not seen by a laser at 0.2 m); a footprint blocks on the shapes whose range overlaps the body's
// (a table top above the robot does not stop it). The default range is every height.
//
// Ray casting walks a uniform grid of buckets (Amanatides & Woo, "A Fast Voxel Traversal Algorithm
// for Ray Tracing", Eurographics 1987): each bucket lists the shapes whose bounding box touches it,
// and the walk stops at the first bucket whose exit lies beyond the nearest hit found so far, so a
// ray costs the shapes near its path, not all shapes. All coordinates are in the world frame [m].
#pragma once

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>

namespace mbot {
namespace core {

using Polygon = std::vector<Eigen::Vector2d>;  ///< vertices in order (either winding), closed implicitly

/// A height range [m above the floor]; a shape from lo to hi.
struct HeightRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  static HeightRange all() { return {}; }
  /// True if the horizontal plane at z cuts the range (NaN: every plane, "no height given").
  bool cuts(double z) const { return std::isnan(z) || (lo <= z && z <= hi); }
  /// True if the ranges share more than a boundary (a box resting on the floor does not touch a
  /// body above the floor).
  bool overlaps(const HeightRange& o) const { return lo < o.hi && o.lo < hi; }
};

/// An occupancy raster in the plane: cell (col, row) covers [col, col + 1) x [row, row + 1) times
/// `resolution` along the raster's own x and y axes, placed at `origin` (the corner of cell (0, 0),
/// world frame [m]) and rotated by `yaw` [rad]. cells[row * width + col] != 0 is solid.
struct GridShape {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double yaw = 0.0;
  double resolution = 0.05;
  int width = 0, height = 0;
  std::vector<unsigned char> cells;
  HeightRange heights;
  bool solid(int col, int row) const {
    return col >= 0 && row >= 0 && col < width && row < height && cells[static_cast<std::size_t>(row) * width + col] != 0;
  }
};

/// Distance [m] from `point` to the solid polygon: 0 inside it, else to its nearest side.
double pointPolygonDistance(const Eigen::Vector2d& point, const Polygon& polygon);

class World2D {
 public:
  /// Bucket edge length [m] of the ray-casting acceleration grid.
  explicit World2D(double bucket_size_m = 0.5);

  /// A box of size (sx, sy) [m] centred at `center` and rotated by yaw [rad].
  void addBox(const Eigen::Vector2d& center, double yaw_rad, double size_x_m, double size_y_m,
              HeightRange heights = HeightRange::all());
  /// A solid convex polygon (its sides become segments; containment counts for overlap tests).
  void addPolygon(const Polygon& polygon, HeightRange heights = HeightRange::all());
  void addCylinder(const Eigen::Vector2d& center, double radius_m, HeightRange heights = HeightRange::all());
  void addSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, HeightRange heights = HeightRange::all());
  /// An occupancy raster; throws std::invalid_argument if its size and cells disagree.
  void addGrid(GridShape grid);

  /// Moving obstacles (other robots' footprints), replaced wholesale each step; tested brute force.
  void setDynamicPolygons(const std::vector<Polygon>& polygons) { dynamic_ = polygons; }
  /// Moving round obstacles (people): each (x, y, radius) [m], replaced wholesale each step; seen by
  /// rays and by overlap tests like any shape, tested brute force.
  void setDynamicCircles(const std::vector<Eigen::Vector3d>& circles) { dynamic_circles_ = circles; }

  /// Distance [m] from `point` to the nearest dynamic polygon (0 inside one), +inf if there is none.
  double distanceToDynamicPolygons(const Eigen::Vector2d& point) const;

  /// Distance [m] from `origin` along `angle_rad` to the first surface, or +inf if none within
  /// `max_range_m`. Dynamic polygon `skip_dynamic` (the caster's own body) is ignored. Static shapes
  /// count only where the plane at `plane_z` [m] cuts them (NaN: all); people and robots always.
  double castRay(const Eigen::Vector2d& origin, double angle_rad, double max_range_m, int skip_dynamic = -1,
                 double plane_z = std::numeric_limits<double>::quiet_NaN()) const;

  /// A whole scan: beam i at yaw + angle_min + i * increment. Ranges follow REP 117: +inf for no
  /// return within range_max, -inf below range_min; gaussian noise of `noise_stddev_m` (if > 0)
  /// is added to returns, which are then quantized to `range_resolution_m` (if > 0).
  void castScan(const Eigen::Vector3d& sensor_pose, double angle_min_rad, double angle_increment_rad, int beams,
                double range_min_m, double range_max_m, double noise_stddev_m, double range_resolution_m,
                std::mt19937& rng, float* out, int skip_dynamic = -1,
                double plane_z = std::numeric_limits<double>::quiet_NaN()) const;

  /// True if the solid polygon touches any dynamic polygon other than `skip_dynamic`, any person, or
  /// any static shape whose height range overlaps `body` (the mover's own, above the floor).
  bool overlaps(const Polygon& polygon, int skip_dynamic = -1, HeightRange body = HeightRange::all()) const;

  int segmentCount() const { return static_cast<int>(segments_.size()); }
  int circleCount() const { return static_cast<int>(circles_.size()); }
  int gridCount() const { return static_cast<int>(grids_.size()); }

 private:
  struct Segment {
    Eigen::Vector2d a, b;
    HeightRange h;
  };
  struct Circle {
    Eigen::Vector2d c;
    double r;
    HeightRange h;
  };
  struct Solid {
    Polygon polygon;
    HeightRange h;
  };
  void rebuildIfNeeded() const;
  void bucketRange(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, int& x0, int& y0, int& x1, int& y1) const;

  double bucket_;
  std::vector<Segment> segments_;
  std::vector<Circle> circles_;
  std::vector<Solid> solids_;     // boxes and polygons, for containment tests
  std::vector<GridShape> grids_;  // rasters: walked cell by cell, not bucketed
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
