// move_base's own parameters (the node's namespace minus its costmaps), ROS-free: ROS's names and
// defaults, the planners it provides, the recovery behaviours, checked with messages that name the
// key (ParamError) and warnings for misspelt or misplaced keys.
#pragma once

#include <string>
#include <vector>

#include "mbot_slam_navigation/core/global_planner.h"
#include "mbot_slam_navigation/core/params.h"
#include "mbot_slam_navigation/core/trajectory_controller.h"

namespace mbot {
namespace core {

enum class RecoveryKind { kClearCostmap, kRotate, kBackUp };

struct RecoveryConfig {
  std::string name, type;
  RecoveryKind kind = RecoveryKind::kClearCostmap;
  // clear_costmap_recovery/ClearCostmapRecovery
  double reset_distance = 3.0;                     ///< [m] side of the square kept
  std::vector<std::string> layer_names = {"obstacle_layer"};
  std::string affected_maps = "both";              ///< local, global or both
  bool force_updating = false, invert_area_to_clear = false;
  // rotate_recovery/RotateRecovery and the back-up recovery
  double sim_granularity = 0.017;                  ///< [rad]
  double frequency = 20.0;                         ///< [Hz]
  double distance = 0.3, speed = 0.1;              ///< [m], [m/s] back-up
};

struct MoveBaseConfig {
  double controller_frequency = 20.0, planner_frequency = 0.0;   ///< [Hz]
  double controller_patience = 15.0, planner_patience = 5.0;     ///< [s]
  long max_planning_retries = -1;
  double oscillation_timeout = 20.0;  ///< [s] ROS's default is 0 (off): a robot rocking forever is what users meet
  double oscillation_distance = 0.5;  ///< [m]
  /// [s] ours, not ROS's: when the path to the goal has not got kGoalProgress_m shorter for this
  /// long, the recoveries run as for oscillation, and after the last the goal is aborted; unlike
  /// oscillation_timeout, driving about does not reset it (a robot circling a person who stands on
  /// its goal). 0 disables.
  double progress_timeout = 60.0;
  /// [s] ours: when something comes up to the standing robot and touches its footprint (a person
  /// walking past or into it), the robot stands this long, or until it is clear, before moving out
  /// with a shrunken footprint: what touched it may walk on into the way out. A touch that begins
  /// while the robot moves (a wall end its turn swung into) is moved out of at once. 0: at once.
  double standing_touch_wait = 3.0;
  bool recovery_behavior_enabled = true, clearing_rotation_allowed = true, shutdown_costmaps = false;
  double conservative_reset_dist = 3.0;
  bool make_plan_clear_costmap = true, make_plan_add_unreachable_goal = true;
  std::string global_type = "navfn/NavfnROS", local_type = "base_local_planner/TrajectoryPlannerROS";
  std::string global_ns, local_ns;    ///< NavfnROS / GlobalPlanner, TrajectoryPlannerROS / DWAPlannerROS
  PlannerParams planner;
  LocalPlannerParams local;
  LocalPlannerRosParams local_ros;
  std::vector<RecoveryConfig> recoveries;
};

/// Reads move_base's namespace `ns` (its values given). `circumscribed_radius` is the local
/// costmap's (the default aggressive_reset clears 4 times it). Throws ParamError naming the key.
MoveBaseConfig readMoveBaseConfig(const ParamValue& values, const std::string& ns, const Warn& warn, double circumscribed_radius);

}  // namespace core
}  // namespace mbot
