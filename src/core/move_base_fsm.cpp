#include "mbot_slam_navigation/core/move_base_fsm.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "mbot_slam_navigation/core/costmap.h"

namespace mbot {
namespace core {
namespace {

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[1024];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buf, sizeof buf, f, args);
  va_end(args);
  return buf;
}

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

double remainingPath(const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector2d& position) {
  if (plan.empty()) return std::numeric_limits<double>::infinity();
  std::size_t nearest = 0;
  for (std::size_t i = 1; i < plan.size(); ++i) {
    if ((plan[i] - position).squaredNorm() < (plan[nearest] - position).squaredNorm()) nearest = i;
  }
  double length = (plan[nearest] - position).norm();
  for (std::size_t i = nearest + 1; i < plan.size(); ++i) length += (plan[i] - plan[i - 1]).norm();
  return length;
}

bool planBlocked(const Costmap& costmap, const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector2d& position,
                 double skip_m, int lethal_cost) {
  if (plan.empty()) return false;
  std::size_t nearest = 0;
  for (std::size_t i = 1; i < plan.size(); ++i) {
    if ((plan[i] - position).squaredNorm() < (plan[nearest] - position).squaredNorm()) nearest = i;
  }
  for (std::size_t i = nearest; i < plan.size(); ++i) {
    if ((plan[i] - position).norm() <= skip_m || (plan[i] - plan.back()).norm() <= skip_m) continue;
    const Cell c = costmap.worldToCell(plan[i]);
    if (!costmap.contains(c)) continue;
    const uint8_t v = costmap.cost(c);
    if (v >= lethal_cost && v != cost::kNoInformation) return true;
  }
  return false;
}

void MoveBaseStateMachine::reset(double now) {
  state_ = MoveBaseState::kPlanning;
  plan_.clear();
  new_plan_ = false;
  last_plan_time_ = -1.0;
  last_valid_plan_ = last_valid_control_ = last_oscillation_reset_ = now;
  oscillation_pose_.reset();
  planning_retries_ = 0;
  recovery_index_ = 0;
  trigger_ = RecoveryTrigger::kNone;
  goal_best_m_ = std::numeric_limits<double>::infinity();
  goal_progress_time_ = now;
  // touching_ is the robot's, not the goal's: a touch the last goal ended in is not new to this
  // one. A hold beyond the wait from now is from before a clock that went back (reset_simulation).
  if (touch_hold_until_ > now + config_.standing_touch_wait) touch_hold_until_ = -1.0;
  why_.clear();
  abort_text_.clear();
}

GoalOutcome MoveBaseStateMachine::abort(const std::string& text, MoveBasePorts& ports) {
  ports.stop();
  abort_text_ = text;
  return GoalOutcome::kAborted;
}

GoalOutcome MoveBaseStateMachine::cycle(double now, const Eigen::Vector3d& goal, MoveBasePorts& ports) {
  std::string why;
  const auto pose = ports.robotPose(why);
  if (!pose) {
    ports.stop();
    ports.warn("pose", "cannot get the robot pose: tf: " + why, 2.0);
    if (now - last_valid_control_ > config_.controller_patience) {
      return abort(fmt("Robot pose unavailable for more than controller_patience %.1f s (tf: %s)", config_.controller_patience,
                       why.c_str()),
                   ports);
    }
    return GoalOutcome::kActive;
  }
  ports.feedback(*pose);

  if (!oscillation_pose_ || (pose->head<2>() - oscillation_pose_->head<2>()).norm() >= config_.oscillation_distance) {
    last_oscillation_reset_ = now;
    oscillation_pose_ = *pose;
    if (trigger_ == RecoveryTrigger::kOscillation) recovery_index_ = 0;
  }

  if (!ports.sensorsCurrent(why)) {
    ports.stop();
    ports.warn("stale", "sensor data is out of date, not commanding the base for safety: " + why, 2.0);
    if (now - last_valid_control_ > config_.controller_patience) {
      return abort(fmt("The local costmap was not current for controller_patience %.1f s: %s", config_.controller_patience,
                       why.c_str()),
                   ports);
    }
    return GoalOutcome::kActive;
  }

  const bool replan_due =
      config_.planner_frequency > 0 && last_plan_time_ >= 0.0 && now - last_plan_time_ >= 1.0 / config_.planner_frequency;
  // Without a map every obstacle is discovered on the way: a plan made through free-looking space
  // runs into them. It is made again as soon as it crosses one, whatever planner_frequency says
  // (with 0, ROS waits for the local planner to fail first, and the robot hesitates before each).
  const bool blocked = state_ == MoveBaseState::kControlling && !replan_due && ports.planBlocked(plan_, *pose);
  if (blocked) ports.info("blocked", "the plan crosses an obstacle seen since it was made; planning again", 5.0);
  if (state_ == MoveBaseState::kPlanning || (state_ == MoveBaseState::kControlling && (replan_due || blocked))) {
    if (!planStep(now, *pose, goal, ports)) return GoalOutcome::kActive;
  }

  if (!plan_.empty()) {
    const double remaining = remainingPath(plan_, pose->head<2>());
    if (remaining < goal_best_m_ - kGoalProgress_m) {
      goal_best_m_ = remaining;
      goal_progress_time_ = now;
      if (trigger_ == RecoveryTrigger::kNoProgress) recovery_index_ = 0;
    }
  }

  if (state_ == MoveBaseState::kControlling) {
    if (const auto outcome = controlStep(now, *pose, goal, ports)) return *outcome;
  }
  if (state_ == MoveBaseState::kClearing) return clearStep(ports);
  return GoalOutcome::kActive;
}

// Plans; false when the cycle ends here (no plan, still within patience).
bool MoveBaseStateMachine::planStep(double now, const Eigen::Vector3d& pose, const Eigen::Vector3d& goal,
                                    MoveBasePorts& ports) {
  std::vector<Eigen::Vector2d> path;
  std::string why;
  const bool ok = ports.makePlan(pose, goal, path, why);
  last_plan_time_ = now;
  if (ok) {
    plan_ = std::move(path);
    new_plan_ = true;
    last_valid_plan_ = now;
    planning_retries_ = 0;
    state_ = MoveBaseState::kControlling;
    ports.planMade(plan_, goal.z());
    return true;
  }
  why_ = why;
  ++planning_retries_;
  if (state_ == MoveBaseState::kControlling) {
    ports.warn("replan", "replanning failed (" + why + "); stopping instead of following the old plan", 0.0);
    state_ = MoveBaseState::kPlanning;
  }
  ports.stop();
  ports.warn("plan", "no plan: " + why, 2.0);
  if (now - last_valid_plan_ > config_.planner_patience ||
      (config_.max_planning_retries >= 0 && planning_retries_ > config_.max_planning_retries)) {
    state_ = MoveBaseState::kClearing;
    trigger_ = RecoveryTrigger::kPlanning;
    return true;
  }
  return false;
}

// The cycle ends here when the goal is reached, or when there is no command and a replan is due.
std::optional<GoalOutcome> MoveBaseStateMachine::controlStep(double now, const Eigen::Vector3d& pose,
                                                             const Eigen::Vector3d& goal, MoveBasePorts& ports) {
  if (new_plan_) {
    ports.followPlan(plan_, goal.z());
    new_plan_ = false;
  }
  const ControlResult control = ports.computeVelocity(pose);
  // Something that comes up to a standing robot and touches it is most likely a person walking
  // past or into it, on the way the robot would move out by: the robot stands until it has passed.
  if (control.touching && !touching_ && control.standing && config_.standing_touch_wait > 0) {
    touch_hold_until_ = now + config_.standing_touch_wait;
  }
  touching_ = control.touching;
  const bool holding = control.touching && now < touch_hold_until_;
  if (holding) {
    ports.info("hold",
               fmt("something came up to the standing robot and touches its footprint (a person walking past?); standing "
                   "still up to standing_touch_wait %.1f s for it to pass before moving out",
                   config_.standing_touch_wait),
               5.0);
  } else if (control.valid && control.footprint_scale < 1.0) {
    // Beside a wall the footprint can touch an inflated obstacle cell; moving out is routine.
    ports.info("footprint",
               fmt("the robot's footprint touches an obstacle in the local costmap where it stands; moving out with the "
                   "footprint shrunk to %.0f%%",
                   100.0 * control.footprint_scale),
               5.0);
  }
  if (!holding && std::isfinite(control.obstacle_inside_m)) {
    ports.warn("inside",
               fmt("an obstacle stands inside the robot's footprint, %.2f m from its centre (a person who walked into "
                   "it?); only moves that keep away from it",
                   control.obstacle_inside_m),
               5.0);
  }
  if (ports.goalReached()) {
    ports.stop();
    return GoalOutcome::kSucceeded;
  }
  ports.controlled();
  if (config_.progress_timeout > 0 && now - goal_progress_time_ > config_.progress_timeout) {
    ports.stop();
    why_ = fmt("the path to the goal has not got %.2f m shorter than %.2f m in progress_timeout %.1f s (something the laser "
               "sees from one side only, a person, may stand on the goal)",
               kGoalProgress_m, goal_best_m_, config_.progress_timeout);
    state_ = MoveBaseState::kClearing;
    trigger_ = RecoveryTrigger::kNoProgress;
  } else if (config_.oscillation_timeout > 0 && now - last_oscillation_reset_ > config_.oscillation_timeout) {
    ports.stop();
    why_ = fmt("moved less than oscillation_distance %.2f m in oscillation_timeout %.1f s", config_.oscillation_distance,
               config_.oscillation_timeout);
    state_ = MoveBaseState::kClearing;
    trigger_ = RecoveryTrigger::kOscillation;
  } else if (control.valid) {
    if (holding) ports.stop();
    else ports.sendVelocity(control.command);
    last_valid_control_ = now;
    if (trigger_ == RecoveryTrigger::kControlling) recovery_index_ = 0;
  } else {
    why_ = control.why;
    ports.stop();
    if (now - last_valid_control_ > config_.controller_patience) {
      state_ = MoveBaseState::kClearing;
      trigger_ = RecoveryTrigger::kControlling;
    } else {
      // No valid command: plan again from here (ROS does the same).
      last_valid_plan_ = now;
      planning_retries_ = 0;
      state_ = MoveBaseState::kPlanning;
      return GoalOutcome::kActive;
    }
  }
  return std::nullopt;
}

GoalOutcome MoveBaseStateMachine::clearStep(MoveBasePorts& ports) {
  const auto& recoveries = config_.recoveries;
  if (trigger_ == RecoveryTrigger::kPlanning && (startsWith(why_, "goal occupied") || startsWith(why_, "goal off the costmap"))) {
    // Turning or backing up cannot free a goal cell or bring it onto the map; only clearing the
    // costmaps might, so the motion recoveries are skipped.
    while (recovery_index_ < recoveries.size() && recoveries[recovery_index_].kind != RecoveryKind::kClearCostmap) {
      ++recovery_index_;
    }
  }
  const char* trigger_text = trigger_ == RecoveryTrigger::kPlanning      ? "no valid plan"
                             : trigger_ == RecoveryTrigger::kControlling ? "no valid control"
                             : trigger_ == RecoveryTrigger::kNoProgress  ? "no progress towards the goal"
                                                                         : "oscillating";
  if (config_.recovery_behavior_enabled && recovery_index_ < recoveries.size()) {
    const auto& r = recoveries[recovery_index_];
    ports.warn("recovery", std::string(trigger_text) + " (" + why_ + "); running recovery behaviour " + r.name, 0.0);
    const double after = ports.runRecovery(r);
    ++recovery_index_;
    last_oscillation_reset_ = last_valid_plan_ = last_valid_control_ = goal_progress_time_ = after;
    planning_retries_ = 0;
    state_ = MoveBaseState::kPlanning;
    return GoalOutcome::kActive;
  }
  const char* text = trigger_ == RecoveryTrigger::kPlanning
                         ? "Failed to find a valid plan. Even after executing recovery behaviors."
                     : trigger_ == RecoveryTrigger::kControlling
                         ? "Failed to find a valid control. Even after executing recovery behaviors."
                     : trigger_ == RecoveryTrigger::kNoProgress
                         ? "Robot is making no progress towards the goal. Even after executing recovery behaviors."
                         : "Robot is oscillating. Even after executing recovery behaviors.";
  return abort(std::string(text) + " Last reason: " + why_, ports);
}

}  // namespace core
}  // namespace mbot
