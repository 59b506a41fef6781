// Rao-Blackwellized particle filter SLAM, GMapping's algorithm (Grisetti et al., IEEE T-RO 2007):
// each particle carries a pose, its trajectory and its own map (SlamGrid, patches shared with its
// relatives). Odometry moves every particle through the motion model; every linearUpdate metres,
// angularUpdate radians or temporalUpdate seconds, a scan is processed:
//   1. each particle's pose is scan-matched against its own map (the mode of the proposal);
//   2. the improved proposal: the scan likelihood is evaluated on a small grid around the matched
//      pose (llsamplerange/llsamplestep in x and y, lasamplerange/lasamplestep in yaw); the particle
//      moves to their likelihood-weighted mean and its weight multiplies by their mean (the
//      proposal's normalizer). Drawing the pose from their gaussian instead only added jitter: it
//      doubled the ACES error (0.22 m against 0.057 m);
//   3. weights are normalized (with ogain flattening them) and, when the effective sample size
//      falls below resampleThreshold * particles, particles are resampled (low variance);
//   4. the scan is registered into every particle's map.
// With scan_odometry (the default), the filter's odometry is not the wheels' but the scan-matched
// track of the pose graph's local SLAM (graph_slam.h with closures off: every scan matched against
// a likelihood grid of the last nodes' scans): the particles then spread from a prediction a few
// centimetres off, not the tens of centimetres of odometry that slips in a turn. On FR079 the
// filter with wheel odometry is lost (1.9 m, as ROS's gmapping), with scan odometry it is not
// (docs/slam.md). Off, the filter is gmapping's.
// Frames: odometry poses are base_footprint in odom; particle poses are base_footprint in map.
#pragma once

#include <memory>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/motion_model.h"
#include "mbot_slam_navigation/core/scan_matcher.h"
#include "mbot_slam_navigation/core/slam_backend.h"
#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace core {

/// The motion noise (srr, srt, str, stt) the node and `slam_offline` give the filter on scan odometry
/// (`~scan_odometry`, the default) unless the user sets it: a tenth of gmapping's 0.1, 0.2, 0.1, 0.2,
/// which are for wheels. The track drifts about a tenth as much; with gmapping's noise the particles
/// spread far wider than its error, walk apart along the corridors and the published best particle
/// changes between lineages a metre apart. Offline on ACES, seeds 0-7, as each scan was processed:
/// median 0.068 m against 0.091 m with gmapping's noise, which lost the map in 2 of 8 (docs/slam.md).
MotionModelParams scanOdometryMotion();

struct RbpfParams {
  int particles = 30;               ///< `particles`
  double linear_update = 1.0;       ///< [m] `linearUpdate`
  double angular_update = 0.5;      ///< [rad] `angularUpdate`
  double temporal_update = -1.0;    ///< [s] `temporalUpdate`; < 0 disables
  double resample_threshold = 0.5;  ///< `resampleThreshold` (fraction of particles)
  double ogain = 3.0;               ///< `ogain`: weights are exp((l - l_max) / (ogain * particles))
  double minimum_score = 0.0;       ///< `minimumScore`: a worse match keeps the odometry pose
  double llsamplerange = 0.01, llsamplestep = 0.01;   ///< [m] proposal sampling in x, y
  double lasamplerange = 0.005, lasamplestep = 0.005; ///< [rad] proposal sampling in yaw
  double delta = 0.05;              ///< [m] map resolution (`delta`)
  double xmin = -100, ymin = -100, xmax = 100, ymax = 100;  ///< [m] initial map extent (grows)
  unsigned seed = 0;
  MotionModelParams motion;         ///< gmapping's; the callers give scanOdometryMotion() with the track
  ScanMatcherParams matcher;
  /// `~scan_odometry`: the filter moves with the scan-matched track (above), not the wheels'.
  bool scan_odometry = true;
  /// `~threads`: threads that match the particles at an update (each its share of them; the
  /// result does not depend on it). Matching is three quarters of the filter's time, and a node
  /// on one thread did not keep up with FR079 played at 10x on a 2-core machine.
  int threads = 2;
  /// `~best_switch_margin`: the particle the filter publishes (pose, map, trajectory) stays in the
  /// lineage it published at the last update, the best of that particle's descendants, unless the
  /// best particle's accumulated weight beats theirs by more than this, in the flattened units the
  /// resampling weighs with (log-likelihood / (ogain * particles)): 4 is a weight 55 times theirs.
  /// 0 is gmapping's choice, the highest accumulated weight at every update. A change of best
  /// particle moves the published pose by the distance between the two lineages, often a metre
  /// before a loop closes, and those jumps were much of the online error (docs/slam.md).
  double best_switch_margin = 4.0;
  /// The track's local SLAM (its `local_*` values, linearUpdate, angularUpdate); its matcher,
  /// delta and map extent are the filter's, and closures are off whatever this says.
  GraphSlamParams tracking;
  void validate() const;  ///< std::invalid_argument naming the gmapping parameter
  /// Gives `g` what both backends share under gmapping's names: the matcher (laser pose and
  /// ranges), angularUpdate, temporalUpdate, delta and the map's extent (not linearUpdate: the
  /// graph has its own default).
  void shareWith(GraphSlamParams& g) const;
};

struct Particle {
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();
  double log_weight = 0.0;     ///< since the last resampling
  double weight_sum = 0.0;     ///< accumulated log-likelihood of the whole history
  SlamGrid map;
  std::shared_ptr<const TrajectoryNode> node;
};

/// Low-variance (systematic) resampling: n = weights.size() evenly spaced pointers starting at
/// `offset` in [0, 1/n) over the cumulative normalized weights; returns the chosen indices, in
/// order. O(n). Any particle with weight above 1/n is chosen at least once.
std::vector<int> lowVarianceResample(const std::vector<double>& weights, double offset);

class RbpfSlam : public SlamBackend {
 public:
  explicit RbpfSlam(const RbpfParams& params);

  /// Feeds one scan with the odometry pose at its time. Returns true when the scan updated the
  /// filter (motion since the last update exceeded the thresholds, or the first scan).
  bool processScan(const Eigen::Vector3d& odom_pose, const LaserScan& scan, double time_s) override;

  /// The particle the filter publishes (`best_switch_margin`), chosen at each update.
  int bestIndex() const { return best_; }
  const Particle& best() const { return particles_[best_]; }
  const std::vector<Particle>& particles() const { return particles_; }
  /// The best particle's pose composed with the filter's odometry (scan_odometry: the track)
  /// since its last update: base in map now.
  Eigen::Vector3d currentPose() const override;
  /// With scan_odometry the pose follows the track at every scan, not only at updates.
  bool tracksEveryScan() const override { return tracker_ != nullptr; }
  double trackingWeakestSigma() const override { return tracker_ ? tracker_->trackingWeakestSigma() : -1.0; }
  /// The best particle's trajectory, oldest first.
  std::vector<TrajectoryNode> trajectory() const override;
  /// The best particle's map.
  OccupancyImage occupancy(double occ_thresh) const override { return best().map.toOccupancy(occ_thresh); }
  /// Entropy of the particles' pose distribution (gaussian fit) [nats].
  double poseEntropy() const;
  double lastNeff() const { return last_neff_; }
  int updates() const override { return updates_; }
  int resamples() const { return resamples_; }
  const RbpfParams& params() const { return params_; }

 private:
  /// Reads only its particle's map and the matcher: safe to run for several particles at once.
  void drawFromProposal(Particle& p, const PreparedScan& scan) const;
  void normalizeAndResample();
  /// Chooses best_ among the particles just updated (their nodes new): see best_switch_margin.
  void choosePublished();

  RbpfParams params_;
  MotionModel motion_;
  ScanMatcher matcher_;
  std::mt19937 rng_;
  std::vector<Particle> particles_;
  bool initialized_ = false;
  std::unique_ptr<GraphSlam> tracker_;  // scan_odometry's track; null without
  // The filter's odometry (the track, or the caller's) at the last scan and at the last update;
  // the trajectory's nodes keep the caller's.
  Eigen::Vector3d last_odom_ = Eigen::Vector3d::Zero(), update_odom_ = Eigen::Vector3d::Zero();
  double linear_distance_ = 0.0, angular_distance_ = 0.0, last_update_time_ = 0.0;
  double last_neff_ = 0.0;
  int best_ = 0;
  std::shared_ptr<const TrajectoryNode> published_;  // best_'s node at the last update
  int updates_ = 0, resamples_ = 0;
};

}  // namespace core
}  // namespace mbot
