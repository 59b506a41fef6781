// Differential-drive (and skid-steer) kinematics as the Gazebo plugins behave, with wheel
// acceleration limits, a command timeout, collisions that stop the robot at the obstacle, and
// odometry integrated from wheel motion with multiplicative slip noise.
//
// Frames: `pose` is base_footprint in the world frame; `odomPose` is base_footprint in odom,
// which starts equal to the spawn pose's identity (odom = where the robot was spawned).
// Units: metres, radians, seconds (REP 103); v forward along base x, w counter-clockwise.
#pragma once

#include <random>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/pose2d.h"
#include "mbot_slam_navigation/core/world2d.h"

namespace mbot {
namespace core {

struct DiffDriveParams {
  double wheel_separation_m = 0.34;      ///< distance between the wheels' contact points
  double wheel_diameter_m = 0.15;
  double wheel_acceleration_mps2 = 0.0;  ///< rim acceleration limit; 0 = unlimited (Gazebo's meaning)
  double cmd_timeout_s = 0.5;            ///< no command for this long stops the robot; <= 0 disables
  double slip_stddev = 0.0;              ///< relative std-dev of each wheel's travel in odometry
  bool odometry_from_world = false;      ///< odometrySource "world": odometry is exact
  HeightRange body;                      ///< [m above the floor] what the body spans; shapes outside it do not stop it
  /// Throws std::invalid_argument naming the field if a value is unusable.
  void validate() const;
};

class DiffDrive {
 public:
  DiffDrive(const DiffDriveParams& params, const Polygon& footprint_in_base, const Eigen::Vector3d& spawn_pose,
            unsigned seed);

  /// Sets the velocity command (v [m/s], w [rad/s]) at simulated time `now_s`. NaN or inf
  /// components are refused (returns false) and the robot keeps its previous command.
  bool command(double v, double w, double now_s);

  /// Advances by dt [s] at time now_s; returns true if the motion was blocked by an obstacle, in
  /// which case the robot stops where it touched (within 1/64 of the step) and its wheels stop.
  bool step(double dt, double now_s, const World2D& world, int self_index = -1);

  /// Teleports (set_model_state, reset): velocities zeroed, odometry untouched.
  void setPose(const Eigen::Vector3d& pose);
  void resetOdometry();

  const Eigen::Vector3d& pose() const { return pose_; }
  const Eigen::Vector3d& odomPose() const { return odom_; }
  double linearVelocity() const { return 0.5 * (wheel_r_ + wheel_l_); }
  double angularVelocity() const { return (wheel_r_ - wheel_l_) / params_.wheel_separation_m; }
  /// Accumulated wheel rotation [rad] (left, right), for wheel joint states.
  Eigen::Vector2d wheelAngles() const { return wheel_angle_; }
  /// The footprint at the current pose, in the world frame.
  Polygon footprintInWorld() const { return footprintAt(pose_); }
  Polygon footprintAt(const Eigen::Vector3d& pose) const;
  const DiffDriveParams& params() const { return params_; }

 private:
  DiffDriveParams params_;
  Polygon footprint_;
  Eigen::Vector3d pose_;
  Eigen::Vector3d odom_ = Eigen::Vector3d::Zero();
  double cmd_v_ = 0.0, cmd_w_ = 0.0, cmd_time_ = -1e300;
  double wheel_l_ = 0.0, wheel_r_ = 0.0;  // rim speeds [m/s]
  Eigen::Vector2d wheel_angle_ = Eigen::Vector2d::Zero();
  std::mt19937 rng_;
};

}  // namespace core
}  // namespace mbot
