#include "mbot_slam_navigation/core/pose2d.h"

#include <cmath>

namespace mbot {
namespace core {

double normalizeAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0.0) a += 2.0 * M_PI;
  return a - M_PI;
}

Eigen::Vector3d composePose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {a.x() + c * b.x() - s * b.y(), a.y() + s * b.x() + c * b.y(), normalizeAngle(a.z() + b.z())};
}

Eigen::Vector3d inversePose(const Eigen::Vector3d& a) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {-c * a.x() - s * a.y(), s * a.x() - c * a.y(), normalizeAngle(-a.z())};
}

Eigen::Vector3d relativePose(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  return composePose(inversePose(from), to);
}

Eigen::Vector3d integrateArc(const Eigen::Vector3d& pose, double ds, double dtheta) {
  // Exact arc for constant velocities; the straight-line limit avoids dividing by a tiny angle.
  Eigen::Vector3d local;
  if (std::abs(dtheta) < 1e-9) {
    local = {ds, 0.0, dtheta};
  } else {
    const double r = ds / dtheta;
    local = {r * std::sin(dtheta), r * (1.0 - std::cos(dtheta)), dtheta};
  }
  return composePose(pose, local);
}

}  // namespace core
}  // namespace mbot
