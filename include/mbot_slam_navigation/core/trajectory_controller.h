// TrajectoryPlannerROS's behaviour around the trajectory planner (local_planner.h), ROS-free.
//
// readLocalPlannerParams reads a TrajectoryPlannerROS namespace with ROS's names, deprecated names
// and effective defaults. TrajectoryController is the per-cycle logic of computeVelocityCommands:
// prune the plan, goal tolerances (with latch_xy_goal_tolerance), stop with the acceleration limits,
// then rotate to the goal yaw, else the best rollout trajectory. Poses are (x [m], y [m], yaw [rad])
// in the local costmap's frame, velocities (vx, vy, vtheta) in the robot's.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/local_planner.h"
#include "mbot_slam_navigation/core/params.h"

namespace mbot {
namespace core {

/// The settings TrajectoryPlannerROS keeps on its ROS side.
struct LocalPlannerRosParams {
  double xy_goal_tolerance = 0.10, yaw_goal_tolerance = 0.05;  ///< [m], [rad]
  bool latch_xy_goal_tolerance = false, prune_plan = true;
  double stop_time_buffer = 0.2;     ///< [s]
  double max_rotational_vel = 1.0;   ///< [rad/s] read by rotate_recovery only
};

/// Reads the namespace (values given, `ns` for messages). `controller_frequency` is move_base's; a
/// controller_frequency inside the namespace wins for the planner's sim_period, as ROS's
/// searchParam finds the nearer one. Throws ParamError naming the key.
void readLocalPlannerParams(const ParamValue& values, const std::string& ns, const Warn& warn, double controller_frequency,
                            LocalPlannerParams& params, LocalPlannerRosParams& ros);

/// ROS's prunePlan: drops the plan points the robot has passed (up to the first within 1 m).
std::vector<Eigen::Vector2d> prunePlan(const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector3d& pose);

struct ControlResult {
  bool valid = false;
  Eigen::Vector3d command = Eigen::Vector3d::Zero();  ///< (vx, vy, vtheta)
  std::string why;                                    ///< why not, when !valid
  double footprint_scale = 1.0;                       ///< < 1: moving out of an obstacle the footprint touched
  double obstacle_inside_m = std::numeric_limits<double>::infinity();  ///< [m] LocalPlanner::lastObstacleInside, when more than a cell inside the outline
  /// A lethal cell touches the footprint's outline or lies inside it where the robot stands (the
  /// robot moves out with a shrunken footprint, or keeps away from what is inside).
  bool touching = false;
  /// The robot's odometry at rest (below kStandingTrans and kStandingRot).
  bool standing = false;
};

class TrajectoryController {
 public:
  static constexpr double kStandingTrans = 0.02;  ///< [m/s] below this (and kStandingRot) the robot stands
  static constexpr double kStandingRot = 0.05;    ///< [rad/s]

  TrajectoryController(const LocalPlannerParams& params, const LocalPlannerRosParams& ros, const Footprint& footprint);
  void setPlan(const std::vector<Eigen::Vector2d>& plan, double goal_yaw);
  void reset();
  /// One control cycle. `reached()` turns true once within both tolerances.
  ControlResult compute(const Costmap& costmap, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity);
  bool reached() const { return reached_; }
  /// LocalPlanner::setSpeedLimit.
  void setSpeedLimit(double max_vel_x) { planner_.setSpeedLimit(max_vel_x); }
  const std::vector<Eigen::Vector2d>& plan() const { return plan_; }
  const std::vector<Eigen::Vector3d>& lastTrajectory() const { return last_trajectory_; }
  const LocalPlannerParams& params() const { return planner_.params(); }
  const LocalPlannerRosParams& rosParams() const { return ros_; }

 private:
  bool safe(const Costmap& costmap, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel, const Eigen::Vector3d& cmd);
  LocalPlanner planner_;
  LocalPlannerRosParams ros_;
  std::vector<Eigen::Vector2d> plan_;
  double goal_yaw_ = 0.0;
  bool reached_ = false, latched_ = false, rotating_to_goal_ = false;
  std::vector<Eigen::Vector3d> last_trajectory_;
};

}  // namespace core
}  // namespace mbot
