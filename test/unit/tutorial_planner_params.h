// The exploration and car tutorials' base_local_planner_params.yaml (config/) where it differs from
// ROS's defaults, as LocalPlannerParams, for the local planner's gtests.
#pragma once

#include "mbot_slam_navigation/core/local_planner.h"

namespace mbot {
namespace core {
namespace test_fixtures {

inline LocalPlannerParams tutorialParams() {
  LocalPlannerParams p;
  p.max_vel_x = 0.3;
  p.min_vel_x = 0.05;
  p.min_in_place_vel_theta = 0.5;
  p.escape_vel = -0.1;
  p.max_vel_theta = 1.0;
  p.min_vel_theta = -1.0;
  p.acc_lim_theta = 3.2;
  p.acc_lim_x = 2.5;
  p.path_distance_bias = 0.8;
  p.goal_distance_bias = 0.4;
  p.holonomic_robot = false;
  p.meter_scoring = true;
  return p;
}

}  // namespace test_fixtures
}  // namespace core
}  // namespace mbot
