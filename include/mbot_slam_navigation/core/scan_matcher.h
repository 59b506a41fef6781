// GMapping's scan matcher (Grisetti, Stachniss, Burgard, "Improved Techniques for Grid Mapping with
// Rao-Blackwellized Particle Filters", IEEE T-RO 23(1), 2007; openslam_gmapping ScanMatcher):
//
// score(pose) = sum over beams of exp(-|d|^2 / sigma), where d is the distance from the beam's end
// point to the mean hit point of the nearest cell within kernelSize cells that is occupied (hits /
// visits > fullness threshold) while the cell one step back along the beam is not (so a beam is
// matched to a surface it could have seen). The log-likelihood of a scan is the sum of
// -|d|^2 / lsigma, or null_likelihood / lsigma for a beam with no such cell.
//
// optimize() climbs that score from an initial pose by steps of lstep [m] in x and y and astep [rad]
// in yaw, halving the steps when no move improves it, `iterations` times: GMapping's choice, kept
// because the benchmark (bench/bench_slam.py) meets its accuracy target with it at a few
// milliseconds per particle and scan.
//
// Frames: poses are the robot base in the map frame; `laser_pose` is the laser in the base frame.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace core {

struct ScanMatcherParams {
  double sigma = 0.05;             ///< [m^2] score kernel: exp(-d^2 / sigma) (gmapping `sigma`)
  int kernel_size = 1;             ///< [cells] search window around each end point (`kernelSize`)
  double lstep = 0.05;             ///< [m] initial linear step (`lstep`)
  double astep = 0.05;             ///< [rad] initial angular step (`astep`)
  int iterations = 5;              ///< step halvings (`iterations`)
  double lsigma = 0.075;           ///< [m^2] likelihood kernel (`lsigma`)
  int lskip = 0;                   ///< beams skipped between used beams (`lskip`)
  double max_urange = 80.0;        ///< [m] usable range: longer returns only clear (`maxUrange`)
  double max_range = 80.0;         ///< [m] returns at or beyond are "no return" (`maxRange`)
  double fullness_threshold = 0.1; ///< occupancy above which a cell can match a beam
  double null_likelihood = -0.5;   ///< log-likelihood of a beam that matches nothing, times lsigma
  Eigen::Vector3d laser_pose = Eigen::Vector3d::Zero();  ///< laser in the base frame (x, y, yaw)
  /// Throws std::invalid_argument naming the gmapping parameter when a value is unusable.
  void validate() const;
};

/// A scan reduced to what matching needs: end points and "one step back" points in the base frame.
struct PreparedScan {
  std::vector<Eigen::Vector2d> hit;
  std::vector<Eigen::Vector2d> free;  ///< hit moved back along the beam by sqrt(2) cells
};

class ScanMatcher {
 public:
  ScanMatcher(const ScanMatcherParams& params, double resolution_m);
  const ScanMatcherParams& params() const { return params_; }

  /// Returns within usable range (every lskip+1-th beam) for matching.
  PreparedScan prepare(const LaserScan& scan) const;
  double score(const SlamGrid& map, const Eigen::Vector3d& pose, const PreparedScan& scan) const;
  /// Score and log-likelihood together (one pass).
  void likelihoodAndScore(const SlamGrid& map, const Eigen::Vector3d& pose, const PreparedScan& scan,
                          double* score, double* log_likelihood, int* matched = nullptr) const;
  /// Hill-climbs from `init`; returns the best pose and writes its score.
  Eigen::Vector3d optimize(const SlamGrid& map, const Eigen::Vector3d& init, const PreparedScan& scan,
                           double* best_score) const;
  /// Integrates a scan into `map` at `pose` (growing it as needed). Beams: NaN, -inf, below
  /// range_min and finite returns at or beyond max_range skipped (gmapping); +inf (REP 117: nothing
  /// within range_max) clears up to min(max_urange, range_max); returns beyond max_urange clear up
  /// to it; others clear up to and mark their end point.
  void registerScan(SlamGrid& map, const Eigen::Vector3d& pose, const LaserScan& scan) const;

 private:
  ScanMatcherParams params_;
  double resolution_;
};

}  // namespace core
}  // namespace mbot
