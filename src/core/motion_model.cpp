#include "mbot_slam_navigation/core/motion_model.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

void MotionModelParams::validate() const {
  const double values[4] = {srr, srt, str, stt};
  const char* names[4] = {"srr", "srt", "str", "stt"};
  for (int i = 0; i < 4; ++i) {
    if (!(values[i] >= 0.0) || !std::isfinite(values[i])) {
      throw std::invalid_argument(std::string(names[i]) + " must be >= 0, got " + std::to_string(values[i]));
    }
  }
}

MotionModel::MotionModel(const MotionModelParams& params) : params_(params) { params_.validate(); }

Eigen::Vector3d MotionModel::stddev(const Eigen::Vector3d& d) const {
  const double sxy = 0.3 * params_.srr;
  return {params_.srr * std::abs(d.x()) + params_.str * std::abs(d.z()) + sxy * std::abs(d.y()),
          params_.srr * std::abs(d.y()) + params_.str * std::abs(d.z()) + sxy * std::abs(d.x()),
          params_.stt * std::abs(d.z()) + params_.srt * std::hypot(d.x(), d.y())};
}

Eigen::Vector3d MotionModel::sample(const Eigen::Vector3d& pose, const Eigen::Vector3d& odom_new,
                                    const Eigen::Vector3d& odom_old, std::mt19937& rng) const {
  const Eigen::Vector3d delta = relativePose(odom_old, odom_new);
  const Eigen::Vector3d sd = stddev(delta);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d noisy(delta.x() + sd.x() * n(rng), delta.y() + sd.y() * n(rng), delta.z() + sd.z() * n(rng));
  noisy.z() = normalizeAngle(noisy.z());
  return composePose(pose, noisy);
}

}  // namespace core
}  // namespace mbot
