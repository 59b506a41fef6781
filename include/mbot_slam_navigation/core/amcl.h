// Adaptive Monte Carlo localization on a known map (Fox 2003; Thrun, Burgard, Fox, "Probabilistic
// Robotics", ch. 8), with ROS amcl's models and parameters:
//  - odometry models "diff" and "omni" (alpha1..alpha5), sampled with standard deviations
//    sqrt(alpha * motion^2). ROS's "diff" and "omni" pass that variance where a standard deviation
//    belongs; here both names mean the corrected model (ROS's "diff-corrected", "omni-corrected").
//  - laser models "likelihood_field" and "beam" (z_hit, z_short, z_max, z_rand, sigma_hit,
//    lambda_short, likelihood_max_dist, max_beams) with ROS's weighting p = 1 + sum(pz^3).
//  - KLD-sampling (min/max_particles, kld_err, kld_z) over 0.5 m x 0.5 m x 10 deg bins, low-variance
//    (systematic) resampling in O(particles), recovery by random particles (alpha_slow, alpha_fast).
// Frames: particles are poses (x [m], y [m], yaw [rad]) of the robot base in the map frame; odometry
// poses are the base in the odom frame; the laser pose is the sensor in the base frame.
#pragma once
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "mbot_slam_navigation/core/laser_scan.h"

namespace mbot {
namespace core {

/// The map as amcl uses it. nav_msgs/OccupancyGrid values: >= 65 occupied, 0..25 free (map_saver's
/// thresholds; ROS amcl takes exactly 100 and 0), anything else unknown.
class AmclMap {
 public:
  /// `data` row-major with row 0 at the lowest y; `origin` the corner of cell (0, 0) [m].
  /// Throws std::invalid_argument for a size mismatch or a non-positive resolution.
  AmclMap(int width, int height, double resolution, const Eigen::Vector2d& origin, const std::vector<int8_t>& data);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }
  /// -1 free, 0 unknown, +1 occupied, as ROS amcl's occ_state; outside the map: 0.
  int state(int x, int y) const;
  /// Indices (y * width + x) of the free cells: where global localization and recovery put particles.
  const std::vector<int>& freeCells() const { return free_cells_; }
  /// Distance [m] from cell centres to the nearest occupied cell centre, capped at max_dist (also the
  /// value outside the map). Computed lazily per max_dist.
  const std::vector<float>& occupiedDistance(double max_dist) const;
  /// Range [m] from (x, y) along `angle` to the first occupied or unknown cell or the map's edge,
  /// capped at max_range (ROS's map_calc_range).
  double castRange(double x, double y, double angle, double max_range) const;

 private:
  int width_, height_;
  double resolution_;
  Eigen::Vector2d origin_;
  std::vector<int8_t> state_;
  std::vector<int> free_cells_;
  mutable double dist_max_ = -1.0;
  mutable std::vector<float> dist_;
};

enum class OdomModel { kDiff, kOmni };
enum class LaserModel { kLikelihoodField, kBeam };

struct AmclParams {
  // Filter (ROS amcl's defaults).
  int min_particles = 100;
  int max_particles = 5000;
  double kld_err = 0.01;
  double kld_z = 0.99;
  double recovery_alpha_slow = 0.0;  ///< 0 disables recovery by random particles
  double recovery_alpha_fast = 0.0;
  // Odometry model.
  OdomModel odom_model = OdomModel::kDiff;
  double alpha1 = 0.2;  ///< rotation noise from rotation
  double alpha2 = 0.2;  ///< rotation noise from translation
  double alpha3 = 0.2;  ///< translation noise from translation
  double alpha4 = 0.2;  ///< translation noise from rotation
  double alpha5 = 0.2;  ///< strafe noise from translation (omni only)
  // Laser model.
  LaserModel laser_model = LaserModel::kLikelihoodField;
  int max_beams = 30;
  double z_hit = 0.95;
  double z_short = 0.1;
  double z_max = 0.05;
  double z_rand = 0.05;
  double sigma_hit = 0.2;            ///< [m]
  double lambda_short = 0.1;         ///< [1/m]
  double likelihood_max_dist = 2.0;  ///< [m]
  /// Throws std::invalid_argument naming the parameter (ROS's name) when out of range.
  void validate() const;
};

struct AmclParticle {
  Eigen::Vector3d pose;  ///< base in the map frame
  double weight;
};

struct AmclEstimate {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();        ///< mean of the heaviest cluster
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< of the whole set (yaw: circular)
  double cluster_weight = 0.0;                           ///< share of the weight in that cluster
  int clusters = 0;
};

class Amcl {
 public:
  Amcl(const AmclParams& params, unsigned seed);

  const AmclParams& params() const { return params_; }
  void setMap(std::shared_ptr<const AmclMap> map);
  bool hasMap() const { return static_cast<bool>(map_); }

  /// max_particles particles drawn from N(mean, cov) (cov: x, y, yaw; yaw wrapped). free_only (with
  /// a map): a draw outside the map's free cells is drawn again (up to 50 times), so that a wide
  /// search puts its particles where the robot can be rather than in walls.
  void initGaussian(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, bool free_only = false);
  /// max_particles particles uniformly over the map's free cells with uniform yaw. Throws
  /// std::logic_error without a map or free cells.
  void initUniform();

  /// Moves every particle by the odometry increment from odom_old to odom_new (base in odom).
  void motionUpdate(const Eigen::Vector3d& odom_old, const Eigen::Vector3d& odom_new);
  /// Weighs the particles by `scan` taken by a laser at `laser_pose` (in the base frame), and
  /// updates the recovery averages. Ranges below range_min count as range_max (as ROS amcl); NaN
  /// and ranges at or beyond range_max are not used by the likelihood field. Returns the number of
  /// beams used. Throws std::logic_error without a map or particles.
  int sensorUpdate(const LaserScan& scan, const Eigen::Vector3d& laser_pose);
  /// KLD-adaptive low-variance resampling (with random particles when recovery is on).
  void resample();

  AmclEstimate estimate() const;
  const std::vector<AmclParticle>& particles() const { return particles_; }
  /// Recovery averages of the total likelihood (ROS's w_slow, w_fast).
  double wSlow() const { return w_slow_; }
  double wFast() const { return w_fast_; }
  /// The mean unnormalized particle weight of the last sensorUpdate (what w_slow and w_fast average).
  double lastAverageWeight() const { return w_avg_; }
  /// The share of the last scan's returns (beams in use, below range_max) that end within
  /// kFitTolerance of an occupied cell seen from the heaviest particle; -1 without returns.
  double lastScanFit() const { return scan_fit_; }
  static constexpr double kFitTolerance = 0.2;  ///< [m]
  /// ROS's pf_resample_limit: the particle count KLD-sampling asks for with k occupied bins.
  int resampleLimit(int k) const;

 private:
  Eigen::Vector3d randomFreePose();
  void normalize();

  AmclParams params_;
  std::mt19937 rng_;
  std::shared_ptr<const AmclMap> map_;
  std::vector<AmclParticle> particles_;
  double w_slow_ = 0.0;
  double w_fast_ = 0.0;
  double w_avg_ = 0.0;
  double scan_fit_ = -1.0;
  // The likelihood field as pz^3 per cell for the last (params, range_max): one lookup per beam.
  std::vector<float> field_;
  float field_outside_ = 0.0f;
  double field_range_max_ = -1.0;
  const AmclMap* field_map_ = nullptr;
};

}  // namespace core
}  // namespace mbot
