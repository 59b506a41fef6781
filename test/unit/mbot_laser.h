// The mbot's laser as the simulator gives it (urdf/xacro/lidar_gazebo.xacro): 360 beams all round,
// 0.1-6 m, 1 cm gaussian noise; for the SLAM gtests.
#pragma once

#include <cmath>
#include <random>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/world2d.h"

namespace mbot {
namespace core {
namespace test_fixtures {

/// A scan of `w` from `pose` (the laser at the base, world frame).
inline LaserScan mbotScanAt(const World2D& w, const Eigen::Vector3d& pose, std::mt19937& rng) {
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = 2.0 * M_PI / 360.0;
  s.range_min_m = 0.1;
  s.range_max_m = 6.0;
  s.ranges_m.resize(360);
  w.castScan(pose, s.angle_min_rad, s.angle_increment_rad, 360, 0.1, 6.0, 0.01, 0.0, rng, s.ranges_m.data());
  return s;
}

}  // namespace test_fixtures
}  // namespace core
}  // namespace mbot
