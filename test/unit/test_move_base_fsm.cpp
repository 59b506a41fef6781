// move_base's state machine on a fake world and a fake clock: patience, retries, oscillation,
// progress, the recoveries in order and what resets them, and the abort texts users read.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/move_base_fsm.h"

namespace {

using mbot::core::ControlResult;
using mbot::core::GoalOutcome;
using mbot::core::MoveBaseConfig;
using mbot::core::MoveBaseState;
using mbot::core::MoveBaseStateMachine;
using mbot::core::ParamValue;
using mbot::core::RecoveryConfig;
using mbot::core::RecoveryTrigger;

// A robot on a straight line: it moves by `speed` times the commanded vx each cycle; plans and
// controls succeed or fail as told.
struct FakeWorld : mbot::core::MoveBasePorts {
  double now = 0.0;
  double dt = 0.1;                     // [s] the control period
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();
  bool pose_ok = true, current = true, plan_ok = true, control_ok = true, reached = false, blocked = false;
  double speed = 1.0;                  // how much of the command the robot achieves
  Eigen::Vector3d command{0.3, 0.0, 0.0};  // the local planner's command when valid
  bool touching = false;               // the footprint touches something where the robot stands
  bool standing = true;                // the last command was a stop or zero
  std::string plan_why = "no path";
  double recovery_s = 3.0;             // [s] each recovery takes
  std::vector<std::string> recoveries_run, warnings;
  int plans = 0, follows = 0, stops = 0;
  Eigen::Vector3d last_command = Eigen::Vector3d::Zero();

  std::optional<Eigen::Vector3d> robotPose(std::string& why) override {
    if (!pose_ok) why = "no transform";
    return pose_ok ? std::optional<Eigen::Vector3d>(pose) : std::nullopt;
  }
  bool sensorsCurrent(std::string& why) override {
    if (!current) why = "scan not updated for 3 s";
    return current;
  }
  bool makePlan(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, std::vector<Eigen::Vector2d>& path,
                std::string& why) override {
    ++plans;
    if (!plan_ok) {
      why = plan_why;
      return false;
    }
    path.clear();  // a straight line, a point every 0.1 m
    const double length = (goal - start).head<2>().norm();
    for (double d = 0.0; d < length; d += 0.1) path.push_back(start.head<2>() + (goal - start).head<2>() * (d / length));
    path.push_back(goal.head<2>());
    return true;
  }
  void planMade(const std::vector<Eigen::Vector2d>&, double) override {}
  bool planBlocked(const std::vector<Eigen::Vector2d>&, const Eigen::Vector3d&) override { return blocked; }
  void followPlan(const std::vector<Eigen::Vector2d>&, double) override { ++follows; }
  ControlResult computeVelocity(const Eigen::Vector3d&) override {
    ControlResult c;
    c.valid = control_ok;
    if (c.valid) c.command = command;
    else c.why = "no valid trajectory";
    c.touching = touching;
    c.standing = standing;
    if (touching) c.footprint_scale = 0.97;
    return c;
  }
  bool goalReached() override { return reached; }
  void sendVelocity(const Eigen::Vector3d& command) override {
    last_command = command;
    standing = command.isZero();
    pose.x() += speed * command.x() * dt;
  }
  void stop() override {
    ++stops;
    last_command.setZero();
    standing = true;
  }
  double runRecovery(const RecoveryConfig& r) override {
    recoveries_run.push_back(r.name);
    now += recovery_s;
    return now;
  }
  void warn(const char*, const std::string& text, double) override { warnings.push_back(text); }
};

MoveBaseConfig defaults() { return mbot::core::readMoveBaseConfig(ParamValue::ofMap(), "/move_base", nullptr, 0.2); }

// Runs cycles until the goal ends or `max_s` simulated seconds pass.
GoalOutcome run(MoveBaseStateMachine& fsm, FakeWorld& w, const Eigen::Vector3d& goal, double max_s) {
  const double end = w.now + max_s;
  while (w.now < end) {
    const GoalOutcome o = fsm.cycle(w.now, goal, w);
    if (o != GoalOutcome::kActive) return o;
    w.now += w.dt;
  }
  return GoalOutcome::kActive;
}

TEST(MoveBaseStateMachine, PlansThenControlsThenSucceeds) {
  MoveBaseStateMachine fsm(defaults());
  FakeWorld w;
  fsm.reset(0.0);
  EXPECT_EQ(fsm.cycle(w.now, {5, 0, 0}, w), GoalOutcome::kActive);
  EXPECT_EQ(fsm.state(), MoveBaseState::kControlling);
  EXPECT_EQ(w.plans, 1);
  EXPECT_EQ(w.follows, 1);
  EXPECT_DOUBLE_EQ(w.last_command.x(), 0.3);
  w.reached = true;
  EXPECT_EQ(fsm.cycle(w.now + 0.1, {5, 0, 0}, w), GoalOutcome::kSucceeded);
  EXPECT_TRUE(w.recoveries_run.empty());
}

TEST(MoveBaseStateMachine, NoPlanWithinPlannerPatienceRunsTheRecoveriesInOrderThenAborts) {
  MoveBaseConfig c = defaults();
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  w.plan_ok = false;
  fsm.reset(0.0);
  // ROS's defaults: planner_patience 5 s; then conservative_reset, rotate_recovery, back_up,
  // aggressive_reset, rotate_recovery, each followed by planner_patience of planning again.
  EXPECT_EQ(run(fsm, w, {5, 0, 0}, 200.0), GoalOutcome::kAborted);
  const std::vector<std::string> expected = {"conservative_reset", "rotate_recovery", "back_up", "aggressive_reset",
                                             "rotate_recovery"};
  EXPECT_EQ(w.recoveries_run, expected);
  EXPECT_EQ(fsm.abortText(), "Failed to find a valid plan. Even after executing recovery behaviors. Last reason: no path");
  // each recovery came after more than planner_patience without a plan
  EXPECT_GT(w.now, c.recoveries.size() * (c.planner_patience + w.recovery_s));
  EXPECT_LT(w.now, c.recoveries.size() * (c.planner_patience + w.recovery_s) + c.planner_patience + 1.0);
}

TEST(MoveBaseStateMachine, AnOccupiedGoalSkipsTheMotionRecoveries) {
  MoveBaseStateMachine fsm(defaults());
  FakeWorld w;
  w.plan_ok = false;
  w.plan_why = "goal occupied: the goal cell is lethal";
  fsm.reset(0.0);
  EXPECT_EQ(run(fsm, w, {5, 0, 0}, 200.0), GoalOutcome::kAborted);
  const std::vector<std::string> expected = {"conservative_reset", "aggressive_reset"};
  EXPECT_EQ(w.recoveries_run, expected);
}

TEST(MoveBaseStateMachine, MaxPlanningRetriesEndsPlanningBeforePatience) {
  MoveBaseConfig c = defaults();
  c.max_planning_retries = 2;
  c.recovery_behavior_enabled = false;
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  w.plan_ok = false;
  fsm.reset(0.0);
  EXPECT_EQ(run(fsm, w, {5, 0, 0}, 10.0), GoalOutcome::kAborted);
  EXPECT_EQ(w.plans, 3);  // the first try and 2 retries
  EXPECT_TRUE(w.recoveries_run.empty());
}

TEST(MoveBaseStateMachine, NoValidControlReplansUntilControllerPatienceThenRecovers) {
  MoveBaseConfig c = defaults();
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  fsm.reset(0.0);
  fsm.cycle(w.now, {5, 0, 0}, w);
  w.control_ok = false;
  w.now += w.dt;
  const int plans_before = w.plans;
  // within controller_patience (15 s) a failed control plans again, no recovery
  while (w.now < c.controller_patience - 1.0) {
    ASSERT_EQ(fsm.cycle(w.now, {5, 0, 0}, w), GoalOutcome::kActive);
    w.now += w.dt;
  }
  EXPECT_GT(w.plans, plans_before + 10);
  EXPECT_TRUE(w.recoveries_run.empty());
  while (w.recoveries_run.empty() && w.now < c.controller_patience + 2.0) {
    fsm.cycle(w.now, {5, 0, 0}, w);
    w.now += w.dt;
  }
  ASSERT_EQ(w.recoveries_run.size(), 1u);
  EXPECT_EQ(fsm.trigger(), RecoveryTrigger::kControlling);
  // a valid command afterwards starts the recoveries from the first again
  w.control_ok = true;
  fsm.cycle(w.now, {5, 0, 0}, w);
  w.now += w.dt;
  fsm.cycle(w.now, {5, 0, 0}, w);
  EXPECT_EQ(fsm.recoveryIndex(), 0u);
}

TEST(MoveBaseStateMachine, ARobotThatDoesNotMoveOscillationDistanceRecoversAfterOscillationTimeout) {
  MoveBaseConfig c = defaults();
  c.progress_timeout = 0.0;  // oscillation alone
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  w.speed = 0.0;  // commands are valid, the robot does not move (wheels spinning, rocking in place)
  fsm.reset(0.0);
  while (w.recoveries_run.empty() && w.now < 60.0) {
    fsm.cycle(w.now, {5, 0, 0}, w);
    w.now += w.dt;
  }
  ASSERT_EQ(w.recoveries_run.size(), 1u);
  EXPECT_EQ(fsm.trigger(), RecoveryTrigger::kOscillation);
  EXPECT_NEAR(w.now - w.recovery_s, c.oscillation_timeout, 0.25);
  EXPECT_EQ(run(fsm, w, {5, 0, 0}, 300.0), GoalOutcome::kAborted);
  EXPECT_EQ(fsm.abortText().rfind("Robot is oscillating.", 0), 0u) << fsm.abortText();
}

TEST(MoveBaseStateMachine, DrivingAboutWithoutGettingNearerEndsAfterProgressTimeout) {
  MoveBaseConfig c = defaults();
  c.oscillation_timeout = 0.0;
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  w.speed = 0.0;
  fsm.reset(0.0);
  EXPECT_EQ(run(fsm, w, {5, 0, 0}, 1000.0), GoalOutcome::kAborted);
  EXPECT_EQ(fsm.trigger(), RecoveryTrigger::kNoProgress);
  EXPECT_EQ(w.recoveries_run.size(), c.recoveries.size());
  EXPECT_NE(fsm.abortText().find("progress_timeout 60.0 s"), std::string::npos) << fsm.abortText();
}

TEST(MoveBaseStateMachine, SlowButSteadyProgressRunsNoRecovery) {
  MoveBaseStateMachine fsm(defaults());
  FakeWorld w;
  w.speed = 0.15;  // 4.5 cm/s: oscillation_distance in 11 s (< 20 s), 0.25 m nearer in 6 s (< 60 s)
  fsm.reset(0.0);
  EXPECT_EQ(run(fsm, w, {50, 0, 0}, 120.0), GoalOutcome::kActive);
  EXPECT_TRUE(w.recoveries_run.empty());
}

TEST(MoveBaseStateMachine, WithoutAPoseOrCurrentSensorsItStopsAndAbortsAfterControllerPatience) {
  MoveBaseConfig c = defaults();
  for (int stale = 0; stale < 2; ++stale) {
    MoveBaseStateMachine fsm(c);
    FakeWorld w;
    (stale ? w.current : w.pose_ok) = false;
    fsm.reset(0.0);
    EXPECT_EQ(run(fsm, w, {5, 0, 0}, 30.0), GoalOutcome::kAborted);
    EXPECT_NEAR(w.now, c.controller_patience, 0.2);
    EXPECT_EQ(w.last_command.x(), 0.0);
    EXPECT_GT(w.stops, 100);
    EXPECT_NE(fsm.abortText().find(stale ? "not current" : "Robot pose unavailable"), std::string::npos);
  }
}

TEST(MoveBaseStateMachine, AFailedReplanWhileMovingStopsTheRobot) {
  MoveBaseConfig c = defaults();
  c.planner_frequency = 1.0;
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  fsm.reset(0.0);
  run(fsm, w, {50, 0, 0}, 1.05);
  EXPECT_EQ(fsm.state(), MoveBaseState::kControlling);
  w.plan_ok = false;
  const int stops = w.stops;
  run(fsm, w, {50, 0, 0}, 1.0);
  EXPECT_EQ(fsm.state(), MoveBaseState::kPlanning);
  EXPECT_GT(w.stops, stops);
  ASSERT_FALSE(w.warnings.empty());
  EXPECT_NE(w.warnings.front().find("stopping instead of following the old plan"), std::string::npos);
}

TEST(MoveBaseStateMachine, APlanThatRunsIntoANewObstacleIsMadeAgainAtOnce) {
  MoveBaseConfig c = defaults();
  ASSERT_EQ(c.planner_frequency, 0.0);  // ROS's default: plan only for a new goal or a failed control
  MoveBaseStateMachine fsm(c);
  FakeWorld w;
  fsm.reset(0.0);
  run(fsm, w, {50, 0, 0}, 2.0);
  EXPECT_EQ(w.plans, 1);
  w.blocked = true;  // an obstacle seen on the way, across the plan
  fsm.cycle(w.now, {50, 0, 0}, w);
  EXPECT_EQ(w.plans, 2);
  EXPECT_EQ(w.follows, 2);  // the local planner follows the new plan in the same cycle
  EXPECT_EQ(fsm.state(), MoveBaseState::kControlling);
  EXPECT_GT(w.last_command.x(), 0.0);
  w.blocked = false;
  run(fsm, w, {50, 0, 0}, 2.0);
  EXPECT_EQ(w.plans, 2);
}

TEST(MoveBaseStateMachine, APlanIsBlockedByAnInscribedCellButNotNearTheRobotTheGoalOrInUnknownSpace) {
  mbot::core::Costmap map(200, 100, 0.05, Eigen::Vector2d(0, 0));  // 10 m x 5 m, free
  std::vector<Eigen::Vector2d> plan;
  for (double x = 1.0; x <= 9.0; x += 0.05) plan.emplace_back(x, 2.5);
  const Eigen::Vector2d robot(1.0, 2.5);
  EXPECT_FALSE(mbot::core::planBlocked(map, plan, robot, 0.3));
  auto mark = [&](double x, uint8_t v) { map.setCost(map.worldToCell(Eigen::Vector2d(x, 2.5)), v); };
  mark(5.0, mbot::core::cost::kNoInformation);
  EXPECT_FALSE(mbot::core::planBlocked(map, plan, robot, 0.3)) << "unknown space does not block";
  mark(1.2, mbot::core::cost::kInscribed);
  mark(8.9, mbot::core::cost::kLethal);
  EXPECT_FALSE(mbot::core::planBlocked(map, plan, robot, 0.3)) << "beside the robot and the goal: the planner allows it";
  mark(6.0, mbot::core::cost::kInscribed);
  EXPECT_TRUE(mbot::core::planBlocked(map, plan, robot, 0.3));
  EXPECT_FALSE(mbot::core::planBlocked(map, plan, Eigen::Vector2d(7.0, 2.5), 0.3)) << "already passed";
  mark(6.0, 252);
  EXPECT_FALSE(mbot::core::planBlocked(map, plan, robot, 0.3)) << "a high cost is passable";
}

TEST(MoveBaseStateMachine, SomethingThatComesUpToTheStandingRobotIsWaitedForBeforeMovingOut) {
  // The robot stands (the local planner's command is zero); a person walks up and touches its
  // footprint. It stands standing_touch_wait (3 s), then moves out; if the person passes first,
  // it goes on at once.
  for (const double passes_after : {10.0, 1.0}) {
    MoveBaseStateMachine fsm(defaults());
    FakeWorld w;
    fsm.reset(0.0);
    w.command.setZero();
    run(fsm, w, {50, 0, 0}, 1.0);
    ASSERT_TRUE(w.standing);
    w.touching = true;
    w.command = Eigen::Vector3d(0.1, 0.0, 0.3);  // the way out
    const double touched = w.now;
    double moved_at = -1.0;
    while (w.now < touched + 6.0 && moved_at < 0.0) {
      if (w.now >= touched + passes_after) w.touching = false;
      fsm.cycle(w.now, {50, 0, 0}, w);
      if (!w.last_command.isZero()) moved_at = w.now;
      w.now += w.dt;
    }
    const double waited = moved_at - touched;
    if (passes_after > 3.0) {
      EXPECT_NEAR(waited, 3.0, 0.11) << "moved out after " << waited << " s";
    } else {
      EXPECT_NEAR(waited, passes_after, 0.11) << "went on " << waited << " s after the touch";
    }
    EXPECT_EQ(fsm.state(), MoveBaseState::kControlling);
    EXPECT_TRUE(w.recoveries_run.empty());
  }
}

TEST(MoveBaseStateMachine, ATouchThatBeginsWhileMovingIsMovedOutOfAtOnce) {
  // A turn swung the footprint into a wall end: the robot's own move, nothing walking. So too
  // with standing_touch_wait 0.
  for (const bool moving : {true, false}) {
    MoveBaseConfig c = defaults();
    if (!moving) c.standing_touch_wait = 0.0;
    MoveBaseStateMachine fsm(c);
    FakeWorld w;
    fsm.reset(0.0);
    if (!moving) w.command.setZero();
    run(fsm, w, {50, 0, 0}, 1.0);
    ASSERT_EQ(w.standing, !moving);
    w.touching = true;
    w.command = Eigen::Vector3d(0.1, 0.0, 0.3);
    fsm.cycle(w.now, {50, 0, 0}, w);
    EXPECT_EQ(w.last_command, w.command) << (moving ? "moving" : "standing_touch_wait 0");
  }
}

TEST(MoveBaseStateMachine, ATouchTheLastGoalEndedInIsNotNewToTheNext) {
  // The robot reached a goal beside a wall with its footprint touching it; the next goal moves it
  // out at once. A touch that came to it between the goals is waited for.
  for (const bool touching_at_the_end : {true, false}) {
    MoveBaseStateMachine fsm(defaults());
    FakeWorld w;
    fsm.reset(0.0);
    w.touching = touching_at_the_end;
    run(fsm, w, {50, 0, 0}, 1.0);
    w.stop();  // the goal ends; the robot stands
    w.now += 5.0;
    w.touching = true;
    fsm.reset(w.now);
    fsm.cycle(w.now, {-50, 0, 0}, w);  // plans, then controls in the same cycle
    EXPECT_EQ(w.last_command.isZero(), !touching_at_the_end)
        << (touching_at_the_end ? "waited for its own touch" : "moved out at once from a new touch");
  }
}

}  // namespace
