// GMapping's odometry motion model: the odometry increment (in the previous odometry pose's frame)
// is perturbed by zero-mean gaussian noise whose standard deviations grow with the motion:
//   sigma_x     = srr |dx| + str |dtheta| + 0.3 srr |dy|
//   sigma_y     = srr |dy| + str |dtheta| + 0.3 srr |dx|
//   sigma_theta = stt |dtheta| + srt sqrt(dx^2 + dy^2)
// (srr: translation from translation [m/m], srt: rotation from translation [rad/m], str: translation
// from rotation [m/rad], stt: rotation from rotation [rad/rad]; ROS defaults 0.1, 0.2, 0.1, 0.2.)
#pragma once

#include <random>

#include <Eigen/Core>

namespace mbot {
namespace core {

struct MotionModelParams {
  double srr = 0.1;
  double srt = 0.2;
  double str = 0.1;
  double stt = 0.2;
  void validate() const;  ///< all >= 0, else std::invalid_argument naming the parameter
};

class MotionModel {
 public:
  explicit MotionModel(const MotionModelParams& params);
  /// Samples the pose that `pose` moves to when odometry goes from odom_old to odom_new.
  Eigen::Vector3d sample(const Eigen::Vector3d& pose, const Eigen::Vector3d& odom_new, const Eigen::Vector3d& odom_old,
                         std::mt19937& rng) const;
  /// The standard deviations (x, y, theta) for an increment (in the old pose's frame).
  Eigen::Vector3d stddev(const Eigen::Vector3d& increment) const;

 private:
  MotionModelParams params_;
};

}  // namespace core
}  // namespace mbot
