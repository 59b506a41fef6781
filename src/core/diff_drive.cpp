#include "mbot_slam_navigation/core/diff_drive.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mbot {
namespace core {

void DiffDriveParams::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string(name) + " must be a positive number, got " + std::to_string(v));
    }
  };
  positive(wheel_separation_m, "wheelSeparation");
  positive(wheel_diameter_m, "wheelDiameter");
  if (!(wheel_acceleration_mps2 >= 0.0)) throw std::invalid_argument("wheelAcceleration must be >= 0");
  if (!(slip_stddev >= 0.0)) throw std::invalid_argument("slip noise must be >= 0");
}

DiffDrive::DiffDrive(const DiffDriveParams& params, const Polygon& footprint_in_base, const Eigen::Vector3d& spawn_pose,
                     unsigned seed)
    : params_(params), footprint_(footprint_in_base), pose_(spawn_pose), rng_(seed) {
  params_.validate();
  if (footprint_.size() < 3) throw std::invalid_argument("DiffDrive: the footprint needs at least 3 vertices");
}

bool DiffDrive::command(double v, double w, double now_s) {
  if (!std::isfinite(v) || !std::isfinite(w)) return false;
  cmd_v_ = v;
  cmd_w_ = w;
  cmd_time_ = now_s;
  return true;
}

Polygon DiffDrive::footprintAt(const Eigen::Vector3d& pose) const {
  Polygon out;
  out.reserve(footprint_.size());
  for (const auto& v : footprint_) out.push_back(composePose(pose, {v.x(), v.y(), 0.0}).head<2>());
  return out;
}

void DiffDrive::setPose(const Eigen::Vector3d& pose) {
  pose_ = pose;
  wheel_l_ = wheel_r_ = 0.0;
}

void DiffDrive::resetOdometry() { odom_.setZero(); }

bool DiffDrive::step(double dt, double now_s, const World2D& world, int self_index) {
  const bool timed_out = params_.cmd_timeout_s > 0.0 && now_s - cmd_time_ > params_.cmd_timeout_s;
  const double v = timed_out ? 0.0 : cmd_v_;
  const double w = timed_out ? 0.0 : cmd_w_;
  const double half = 0.5 * params_.wheel_separation_m;
  const double target[2] = {v - w * half, v + w * half};
  double* wheel[2] = {&wheel_l_, &wheel_r_};
  for (int k = 0; k < 2; ++k) {
    if (params_.wheel_acceleration_mps2 > 0.0) {
      const double max_change = params_.wheel_acceleration_mps2 * dt;
      *wheel[k] += std::clamp(target[k] - *wheel[k], -max_change, max_change);
    } else {
      *wheel[k] = target[k];
    }
  }
  double dl = wheel_l_ * dt, dr = wheel_r_ * dt;

  // Move, and if the new footprint touches something, bisect for the last free fraction.
  auto poseAt = [&](double f) { return integrateArc(pose_, 0.5 * f * (dl + dr), f * (dr - dl) / params_.wheel_separation_m); };
  bool blocked = false;
  Eigen::Vector3d next = poseAt(1.0);
  if ((dl != 0.0 || dr != 0.0) && world.overlaps(footprintAt(next), self_index, params_.body)) {
    blocked = true;
    double free = 0.0, hit = 1.0;
    for (int i = 0; i < 6; ++i) {
      const double mid = 0.5 * (free + hit);
      (world.overlaps(footprintAt(poseAt(mid)), self_index, params_.body) ? hit : free) = mid;
    }
    next = poseAt(free);
    dl *= free;
    dr *= free;
    wheel_l_ = wheel_r_ = 0.0;
  }
  pose_ = next;
  wheel_angle_ += Eigen::Vector2d(dl, dr) / (0.5 * params_.wheel_diameter_m);

  // Odometry sees the wheels' travel, each with slip noise proportional to it.
  if (params_.slip_stddev > 0.0 && !params_.odometry_from_world) {
    std::normal_distribution<double> slip(0.0, params_.slip_stddev);
    dl *= 1.0 + slip(rng_);
    dr *= 1.0 + slip(rng_);
  }
  odom_ = integrateArc(odom_, 0.5 * (dl + dr), (dr - dl) / params_.wheel_separation_m);
  return blocked;
}

}  // namespace core
}  // namespace mbot
