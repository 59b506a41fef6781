// A log-odds occupancy grid (Moravec & Elfes 1985; Thrun, Burgard, Fox, "Probabilistic Robotics",
// ch. 9): each cell stores l = log(p / (1 - p)) of being occupied, updated additively by beams and
// clamped so that the map can still change its mind. Cells never touched by a beam are "unknown".
//
// Geometry: `origin` is the world position [m] of the outer corner of cell (0, 0) in the grid's
// frame (map or odom); cell (x, y) covers [origin + (x, y) * resolution, origin + (x+1, y+1) *
// resolution). Rows grow with y, as in nav_msgs/OccupancyGrid's data layout.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/cell.h"
#include "mbot_slam_navigation/core/laser_scan.h"

namespace mbot {
namespace core {

/// How much one observation moves a cell, in log-odds units.
struct LogOddsModel {
  float hit = 0.85f;    ///< added to a beam's end cell when it hit something (p = 0.70)
  float miss = -0.4f;   ///< added to every cell a beam passed through (p = 0.40)
  float min = -5.0f;    ///< lower clamp (p = 0.0067), keeps free space revisable
  float max = 5.0f;     ///< upper clamp (p = 0.9933)

  /// Builds the model from probabilities in (0, 1): p_hit > 0.5 > p_miss. Throws
  /// std::invalid_argument naming the offending argument otherwise.
  static LogOddsModel fromProbabilities(double p_hit, double p_miss);
};

/// Log-odds of probability p, p in (0, 1).
float probabilityToLogOdds(double p);
/// Probability of log-odds l.
double logOddsToProbability(float l);

class OccupancyGrid {
 public:
  /// Throws std::invalid_argument (naming the argument) for a non-positive size or resolution.
  OccupancyGrid(int width_cells, int height_cells, double resolution_m, const Eigen::Vector2d& origin_m,
                const LogOddsModel& model = LogOddsModel());

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }
  const LogOddsModel& model() const { return model_; }

  bool contains(const Cell& c) const { return c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_; }
  /// The cell containing world point p [m]; may lie outside the grid (check with contains()).
  Cell worldToCell(const Eigen::Vector2d& p) const;
  /// World position [m] of the centre of cell c (defined outside the grid too).
  Eigen::Vector2d cellCenter(const Cell& c) const;

  /// Cell accessors; throw std::out_of_range naming the cell and the grid size when c is outside.
  float logOdds(const Cell& c) const;
  double probability(const Cell& c) const { return logOddsToProbability(logOdds(c)); }
  bool observed(const Cell& c) const;
  void setLogOdds(const Cell& c, float l);

  /// Integrates one beam from `from` to `to` (world, m): every cell before the end becomes freer;
  /// the end cell becomes more occupied when `hit`, freer otherwise. Cells outside are skipped.
  void integrateBeam(const Eigen::Vector2d& from, const Eigen::Vector2d& to, bool hit);

  /// Integrates a scan taken by a sensor at `sensor_pose` (x [m], y [m], yaw [rad] in the grid's
  /// frame). Returns within `usable_range_m` (and range_max) mark their end; +inf and returns at or
  /// beyond range_max clear up to min(usable_range_m, range_max); NaN, -inf and returns below
  /// range_min are skipped. Returns the number of beams used.
  int integrateScan(const Eigen::Vector3d& sensor_pose, const LaserScan& scan, double usable_range_m);

  /// Enlarges the grid so that p (world, m) lies at least `margin_m` inside it, keeping every cell's
  /// value and world position (the origin moves by whole cells). No-op if already inside.
  void growToInclude(const Eigen::Vector2d& p, double margin_m);

  /// nav_msgs/OccupancyGrid data: -1 unknown, otherwise round(100 * p); row-major from row 0.
  std::vector<int8_t> toRosData() const;
  /// Number of observed cells.
  int observedCount() const;

 private:
  std::size_t index(const Cell& c) const { return static_cast<std::size_t>(c.y) * width_ + c.x; }
  void checkContains(const Cell& c) const;
  void addLogOdds(const Cell& c, float delta);

  int width_;
  int height_;
  double resolution_;
  Eigen::Vector2d origin_;
  LogOddsModel model_;
  std::vector<float> log_odds_;
  std::vector<uint8_t> observed_;
};

}  // namespace core
}  // namespace mbot
