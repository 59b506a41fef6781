// Correlative scan matching for the pose-graph SLAM backend.
//
// A LikelihoodGrid holds, for every cell, how well a laser end point there would agree with a set
// of reference points (earlier scans): exp(-d^2 / (2 sigma^2)) of the distance d to the nearest
// reference point, stored as 0..65535 (Olson, "Real-Time Correlative Scan Matching", ICRA 2009,
// stores 0..255: then every cell within 0.066 sigma of a reference point, 5 mm for a 0.075 m
// kernel, holds the same 255, too coarse to tell poses apart near the surface; 16 bits made
// fewer bent maps of the large floor, docs/slam.md).
// The score of a pose is the mean of that value over the scan's points, in [0, 1].
//
// matchBranchAndBound() finds the best-scoring pose in a window (x, y within +-linear, yaw within
// +-angular of an initial pose) exactly, at the grid's resolution and an angular step that moves
// the farthest point by at most one cell, without visiting every pose: it scores coarse blocks of
// translations on max-pooled copies of the grid (an upper bound of every pose in the block) and
// only descends into blocks whose bound beats the best pose found so far (Hess, Kohler, Rapp,
// Andor, "Real-Time Loop Closure in 2D LIDAR SLAM", ICRA 2016, section V). refine() then climbs the
// bicubically interpolated score below the grid's resolution.
//
// Frames: the grid and every pose live in one "reference" frame (the map frame for local
// matching, a submap's anchor node for loop closure); scan points are in the robot base frame.
// Units: metres and radians.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/laser_scan.h"

namespace mbot {
namespace core {

class LikelihoodGrid {
 public:
  using Value = uint16_t;
  static constexpr double kMax = 65535.0;  ///< the value of a cell on a reference point
  /// A grid covering `points` (reference frame, m) plus the kernel's reach, at `resolution_m`;
  /// `sigma_m` is the kernel's standard deviation. Throws std::invalid_argument on bad values.
  LikelihoodGrid(const std::vector<Eigen::Vector2d>& points, double resolution_m, double sigma_m);

  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }  ///< corner of cell (0, 0) [m]
  int width() const { return width_; }
  int height() const { return height_; }
  /// Value 0..kMax of cell (x, y); 0 outside.
  int value(int x, int y) const {
    return (x < 0 || y < 0 || x >= width_ || y >= height_) ? 0 : cells_[static_cast<std::size_t>(y) * width_ + x];
  }
  /// Bicubic (Catmull-Rom) interpolation of the values at a point of the reference frame, about
  /// [0, 1] (cubic convolution may overshoot by a few percent next to a peak).
  double interpolated(const Eigen::Vector2d& p) const;
  /// Mean interpolated value of the points moved by `pose`, in [0, 1] (0 for no points).
  double score(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector3d& pose) const;

  /// Level h of the max-pooling pyramid as an array: level 0 is the grid; in level h >= 1 the
  /// value at (x, y) is the largest level-0 value in the block [x, x + 2^h) x [y, y + 2^h), stored
  /// at index (y + pad) * width + x + pad, pad = 2^h - 1 (x and y may be as low as -pad).
  struct Level {
    const Value* data;
    int width, height, pad;
    /// The value at (x, y); 0 outside.
    int at(int x, int y) const {
      x += pad;
      y += pad;
      return (x < 0 || y < 0 || x >= width || y >= height) ? 0 : data[static_cast<std::size_t>(y) * width + x];
    }
  };
  /// Level h (built by buildLevels(h + 1) or by the matcher; h = 0 is always there).
  Level level(int h) const {
    if (h == 0) return {cells_.data(), width_, height_, 0};
    const int pad = (1 << h) - 1;
    return {levels_[h - 1].data(), width_ + pad, height_ + pad, pad};
  }
  /// Max-pooled level h: level(h).at(x, y).
  int pooled(int h, int x, int y) const { return level(h).at(x, y); }
  /// Builds levels 1..levels-1 now (they are otherwise built lazily by the matcher).
  void buildLevels(int levels) const;
  /// Frees the pooled levels (they are rebuilt on the next match). Not thread-safe: a grid is
  /// matched and trimmed by one thread.
  void dropLevels() const;
  /// Bytes held (base grid and pooled levels), for cache accounting.
  std::size_t bytes() const;

 private:
  double resolution_;
  Eigen::Vector2d origin_;
  int width_ = 0, height_ = 0;
  std::vector<Value> cells_;
  mutable std::vector<std::vector<Value>> levels_;  // levels_[h - 1] is level h
};

struct MatchWindow {
  double linear_m = 0.3;    ///< search x and y within +- this of the initial pose
  double angular_rad = 0.3; ///< search yaw within +- this
};

struct MatchResult {
  bool found = false;       ///< a pose scored above the minimum
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();
  double score = 0.0;       ///< in [0, 1]
};

/// The end points of a scan usable for matching, in the robot base frame: finite returns within
/// [range_min, min(max_range, range_max)), thinned to one point per `voxel_m` square (the first).
std::vector<Eigen::Vector2d> matchPoints(const LaserScan& scan, const Eigen::Vector3d& laser_pose, double max_range_m,
                                         double voxel_m);

/// matchPoints, and the surface between two neighbouring beams' returns filled in every `voxel_m`
/// where the returns lie no farther apart than a surface seen at a grazing angle would put them
/// (4 beam spacings at their range, 0.3 m at most, 2 voxel_m at least): a wall far down a corridor
/// is hit only every few decimetres, and a map made of those hits alone scores a scan higher the
/// nearer it is moved to where the map was seen from. For the local map that scans are tracked in.
std::vector<Eigen::Vector2d> surfacePoints(const LaserScan& scan, const Eigen::Vector3d& laser_pose, double max_range_m,
                                           double voxel_m);

/// Unit normals of a scan's `points` (in beam order, as matchPoints gives them), each facing
/// `origin` (the laser, same frame), from the neighbours either side; zero where a neighbour lies
/// farther than `max_gap_m` (an edge: the surface's side is not known) and at both ends.
std::vector<Eigen::Vector2d> surfaceNormals(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& origin,
                                            double max_gap_m);

/// What a set of scans could see, for leaving out of a match the returns that the reference scans
/// could not have seen: a point counts as seen when some scan's beam nearest its bearing reached
/// at least that far, within a tolerance; a beam without a return reached its maximum range. A
/// scan tracked while the robot drives on sees, besides what the map holds, what came into view
/// (behind door jambs and corners, round the robot's new position); those returns lie next to the
/// map's edges and score higher the farther back the scan is put. Measured on an office run's
/// scans with ground truth, pairs of scans 2 m apart, one scan matched in a map of the other:
/// with every return the scan is put back by 1.3% of the distance (mean; 2.1 cm median); with the
/// seen returns only (a cell of tolerance), 0.2% forward. With the farther of the two beams either
/// side instead of the nearest, 0.6% back; with two cells of tolerance, 0.5% back.
/// Frames: every pose in the reference frame, as the grid's.
class Visibility {
 public:
  /// Adds what `scan` saw from `pose` (the base in the reference frame), its beams from
  /// `laser_pose` in the base frame, reaching at most `max_range_m`.
  void add(const LaserScan& scan, const Eigen::Vector3d& laser_pose, const Eigen::Vector3d& pose, double max_range_m);
  /// Whether some added scan saw `p` (reference frame), with `tolerance_m` beyond its returns;
  /// with `normal` (reference frame, unit, the side of the surface at `p` that counts), only a scan
  /// from that side counts: a wall's other face lies a wall's thickness behind this one, within
  /// the tolerance of a pose a few centimetres off.
  bool seen(const Eigen::Vector2d& p, double tolerance_m, const Eigen::Vector2d* normal = nullptr) const;
  /// The `points` (base frame) that some added scan saw when the base is at `pose`; with `normals`
  /// (base frame, one per point as surfaceNormals gives them), only from the side of the surface
  /// they face.
  std::vector<Eigen::Vector2d> seenOf(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector3d& pose,
                                      double tolerance_m, const std::vector<Eigen::Vector2d>* normals = nullptr) const;
  /// The `points` (base frame, `normals` as for seenOf) less those on the back of a surface that
  /// only scans from its other side saw: a point whose own side no added scan saw, while one from
  /// the other side reached to within `behind_m` of it (a wall's thickness and a pose's slack), is
  /// the other face of a wall the scans hold, and matched to it would put the scan a wall's
  /// thickness off. Points without a normal, and points nobody saw, are kept.
  std::vector<Eigen::Vector2d> notBehindOf(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector3d& pose,
                                           double tolerance_m, double behind_m,
                                           const std::vector<Eigen::Vector2d>& normals) const;
  bool empty() const { return views_.empty(); }
  void clear() { views_.clear(); }

 private:
  struct View {
    Eigen::Vector2d origin;    // the laser in the reference frame
    double first_angle = 0.0;  // of beam 0, reference frame [rad]
    double increment = 0.0;    // [rad]
    bool all_round = false;    // the last beam is next to the first
    std::vector<float> reach;  // [m] per beam: its return, its maximum range, or 0 (no usable reading)
  };
  std::vector<View> views_;
};

/// The best pose of `points` (base frame) in `window` around `init`, if one scores above
/// `min_score`. Candidates within `exclude_radius_m` / `exclude_angle_rad` of `exclude` (when
/// `exclude` is given) are skipped: used to look for a second, different good match.
MatchResult matchBranchAndBound(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                                const Eigen::Vector3d& init, const MatchWindow& window, double min_score,
                                const Eigen::Vector3d* exclude = nullptr, double exclude_radius_m = 0.0,
                                double exclude_angle_rad = 0.0);

/// How sharply the score falls off around `pose` in each direction: minus its Hessian in (x [m],
/// y [m], yaw [rad]) of the reference frame, by central differences (steps of half a cell, and the
/// yaw that moves the points' mean range by half a cell), with negative eigenvalues set to 0. In
/// score units per m^2 (per m rad, per rad^2). Along a plain corridor the x-x entry is about 0:
/// the scan does not say where along it the robot is; a return on a surface square to a direction
/// adds about 1 / (sigma^2 n) to it (sigma the grid's kernel, n the returns), so a direction that
/// every return pins has about 1 / sigma^2.
Eigen::Matrix3d scoreCurvature(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                               const Eigen::Vector3d& pose);

/// The directions a match fixes and those it leaves open: the eigenvectors of scoreCurvature with
/// the yaw scaled to metres at the returns' mean range (a turn by a moves them by about range * a),
/// so that x, y and yaw compare. Coupled directions show as such: a lone pillar fixes the distance
/// and the bearing to it, but not a turn around it (a step sideways and a turn together), which the
/// x-y block alone would call pinned.
struct MatchDirections {
  Eigen::Matrix3d vectors = Eigen::Matrix3d::Identity();  ///< columns: unit (x [m], y [m], range * yaw [m])
  Eigen::Vector3d values = Eigen::Vector3d::Zero();       ///< curvature along each [score/m^2], ascending
  double range_m = 1.0;                                   ///< [m] the returns' mean range, the yaw's scale
  /// (x [m], y [m], yaw [rad]) as (x, y, range * yaw) [m].
  Eigen::Vector3d scaled(const Eigen::Vector3d& delta) const;
  /// `delta` (x, y, yaw), the match's step from a prediction, with its components along the
  /// directions curving less than `min_curvature` weighed against the prediction's own curvature
  /// `prior_curvature` [score/m^2] (kept in the share values / (values + prior_curvature), the
  /// Gaussian fusion of the two): where the scan says little, the prediction decides.
  Eigen::Vector3d weighOpen(const Eigen::Vector3d& delta, double min_curvature, double prior_curvature) const;
};
MatchDirections matchDirections(const Eigen::Matrix3d& curvature, const std::vector<Eigen::Vector2d>& points);

/// Hill-climbs the interpolated score from `init` with steps from half a cell and `angular_step`,
/// halved `halvings` times; returns the pose and writes its score. With `prior_weight` > 0 it climbs
/// score - prior_weight * |xy - init xy|^2 [1/m^2] instead (a pull back to `init` where the score is
/// nearly flat) and still writes the plain score.
Eigen::Vector3d refineMatch(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                            const Eigen::Vector3d& init, double angular_step_rad, int halvings, double* score,
                            double prior_weight = 0.0);

}  // namespace core
}  // namespace mbot
