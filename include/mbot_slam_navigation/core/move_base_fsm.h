// move_base's state machine, ROS-free: planning, controlling and clearing, with ROS's patience
// rules (planner_patience, max_planning_retries, controller_patience), oscillation detection,
// ~progress_timeout, and the recovery behaviours in order. The node (move_base_node.cpp) gives it
// the world through MoveBasePorts (tf, the costmaps' state, the planners, cmd_vel, the recoveries)
// and calls cycle() at controller_frequency; the gtests give it a fake world and a fake clock.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/move_base_config.h"
#include "mbot_slam_navigation/core/trajectory_controller.h"

namespace mbot {
namespace core {

/// What the state machine asks of the node. Poses are (x [m], y [m], yaw [rad]) in the global
/// costmap's frame; velocities (vx [m/s], vy [m/s], vtheta [rad/s]) in the robot's frame.
class MoveBasePorts {
 public:
  virtual ~MoveBasePorts() = default;
  /// The robot's pose, or nullopt with why.
  virtual std::optional<Eigen::Vector3d> robotPose(std::string& why) = 0;
  /// Whether the local costmap's sensors are current (else the robot must not move), and why not.
  virtual bool sensorsCurrent(std::string& why) = 0;
  /// A global plan from `start` to `goal`; false with why (a why starting "goal occupied" or "goal
  /// off the costmap" skips the motion recoveries: they cannot free a goal).
  virtual bool makePlan(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, std::vector<Eigen::Vector2d>& path,
                        std::string& why) = 0;
  /// A new global plan was made (to publish).
  virtual void planMade(const std::vector<Eigen::Vector2d>& path, double goal_yaw) = 0;
  /// Whether the plan, from the robot's `pose` (this cycle's) on, now crosses an obstacle the
  /// global costmap did not hold when it was made (checked every cycle while controlling; a
  /// blocked plan is made again at once).
  virtual bool planBlocked(const std::vector<Eigen::Vector2d>& path, const Eigen::Vector3d& pose) {
    (void)path, (void)pose;
    return false;
  }
  /// The local planner is to follow this plan from now on.
  virtual void followPlan(const std::vector<Eigen::Vector2d>& path, double goal_yaw) = 0;
  /// The local planner's command for this cycle, the robot at `pose` (invalid with why).
  virtual ControlResult computeVelocity(const Eigen::Vector3d& pose) = 0;
  /// Whether the local planner considers the goal reached.
  virtual bool goalReached() = 0;
  virtual void sendVelocity(const Eigen::Vector3d& command) = 0;
  virtual void stop() = 0;
  /// Runs one recovery behaviour to its end; returns the time [s] then.
  virtual double runRecovery(const RecoveryConfig& recovery) = 0;
  /// Each cycle with a pose (the action's feedback).
  virtual void feedback(const Eigen::Vector3d& pose) { (void)pose; }
  /// After each control step (the local plan to publish).
  virtual void controlled() {}
  /// A warning; `key` names its kind, `throttle_s` > 0 asks to repeat it at most that often.
  virtual void warn(const char* key, const std::string& text, double throttle_s) = 0;
  /// Information: something handled as a matter of course (same arguments).
  virtual void info(const char* key, const std::string& text, double throttle_s) {
    (void)key, (void)text, (void)throttle_s;
  }
};

enum class MoveBaseState { kPlanning, kControlling, kClearing };
/// Why the recoveries run.
enum class RecoveryTrigger { kNone, kPlanning, kControlling, kOscillation, kNoProgress };
enum class GoalOutcome { kActive, kSucceeded, kAborted };

class MoveBaseStateMachine {
 public:
  /// [m] the path to the goal this much shorter counts as progress (progress_timeout)
  static constexpr double kGoalProgress_m = 0.25;

  explicit MoveBaseStateMachine(const MoveBaseConfig& config) : config_(config) {}

  /// A new goal from `now` [s] on.
  void reset(double now);
  /// One control cycle at time `now` [s] towards `goal`; kAborted with abortText().
  GoalOutcome cycle(double now, const Eigen::Vector3d& goal, MoveBasePorts& ports);

  MoveBaseState state() const { return state_; }
  RecoveryTrigger trigger() const { return trigger_; }
  /// Index of the next recovery behaviour in config().recoveries.
  std::size_t recoveryIndex() const { return recovery_index_; }
  const std::string& abortText() const { return abort_text_; }
  const std::vector<Eigen::Vector2d>& plan() const { return plan_; }
  const MoveBaseConfig& config() const { return config_; }

 private:
  GoalOutcome abort(const std::string& text, MoveBasePorts& ports);
  bool planStep(double now, const Eigen::Vector3d& pose, const Eigen::Vector3d& goal, MoveBasePorts& ports);
  /// The goal's outcome when the cycle ends in the control step; nullopt to go on.
  std::optional<GoalOutcome> controlStep(double now, const Eigen::Vector3d& pose, const Eigen::Vector3d& goal,
                                         MoveBasePorts& ports);
  GoalOutcome clearStep(MoveBasePorts& ports);

  MoveBaseConfig config_;
  MoveBaseState state_ = MoveBaseState::kPlanning;
  RecoveryTrigger trigger_ = RecoveryTrigger::kNone;
  std::vector<Eigen::Vector2d> plan_;
  bool new_plan_ = false;
  double last_plan_time_ = -1.0;  ///< < 0: never planned for this goal
  double last_valid_plan_ = 0.0, last_valid_control_ = 0.0, last_oscillation_reset_ = 0.0;
  std::optional<Eigen::Vector3d> oscillation_pose_;
  long planning_retries_ = 0;
  std::size_t recovery_index_ = 0;
  double goal_best_m_ = std::numeric_limits<double>::infinity();
  double goal_progress_time_ = 0.0;
  bool touching_ = false;          ///< the last control step's ControlResult::touching (kept across goals)
  double touch_hold_until_ = -1.0;  ///< [s] standing_touch_wait ends then
  std::string why_, abort_text_;
};

/// [m] Along `plan` from its point nearest `position` to its end, plus the way to that point;
/// infinity for an empty plan.
double remainingPath(const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector2d& position);

class Costmap;
/// Whether `plan`, from its point nearest `position` on and leaving out the points within `skip_m`
/// [m] of it and of the plan's end (the robot may stand in an inflated zone, the goal may lie in
/// one: the planner allows both), crosses a lethal cell or one at or above `lethal_cost` (the
/// global planner's: the robot cannot pass there). Unknown cells and points off the costmap do not
/// block (the planners cross unknown space).
bool planBlocked(const Costmap& costmap, const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector2d& position,
                 double skip_m, int lethal_cost = 253);

}  // namespace core
}  // namespace mbot
