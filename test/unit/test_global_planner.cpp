#include <cmath>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/global_planner.h"

using namespace mbot::core;

namespace {
double pathLength(const std::vector<Eigen::Vector2d>& p) {
  double l = 0;
  for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}
// 10 x 10 cells of 1 m with a wall at x = 5 from y = 0 to 7 (a gap at the top).
Costmap wallMap() {
  Costmap m(10, 10, 1.0, {0, 0});
  for (int y = 0; y < 8; ++y) m.setCost({5, y}, cost::kLethal);
  return m;
}
bool touchesObstacle(const Costmap& m, const std::vector<Eigen::Vector2d>& path) {
  for (const auto& p : path) {
    if (m.cost(m.worldToCell(p)) >= cost::kInscribed) return true;
  }
  return false;
}
}  // namespace

class BothPlanners : public ::testing::TestWithParam<bool> {};

TEST_P(BothPlanners, StraightLineOnAnEmptyGridIsOptimal) {
  Costmap m(20, 20, 0.5, {0, 0});
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Plan plan = planner.makePlan(m, {1.25, 1.25}, {8.25, 1.25});
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_NEAR(pathLength(plan.path), 7.0, 1e-9);
  EXPECT_NEAR((plan.path.front() - Eigen::Vector2d(1.25, 1.25)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((plan.path.back() - Eigen::Vector2d(8.25, 1.25)).norm(), 0.0, 1e-9);
  const Plan diagonal = planner.makePlan(m, {0.25, 0.25}, {9.75, 9.75});
  ASSERT_EQ(diagonal.status, PlanStatus::kOk);
  EXPECT_NEAR(pathLength(diagonal.path), 19 * 0.5 * std::sqrt(2.0), 0.05);
}

TEST_P(BothPlanners, GoesAroundAWallNeverThroughIt) {
  const Costmap m = wallMap();
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Plan plan = planner.makePlan(m, {2.5, 2.5}, {8.5, 2.5});
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_FALSE(touchesObstacle(m, plan.path));
  bool through_gap = false;
  for (const auto& q : plan.path) through_gap = through_gap || (m.worldToCell(q).x == 5 && q.y() > 8.0);
  EXPECT_TRUE(through_gap);
  // The shortest 8-connected way that does not cut the wall's end: 10 straight steps and 4
  // diagonals (the two steps round the wall's end cannot be diagonal).
  EXPECT_NEAR(pathLength(plan.path), 10 + 4 * std::sqrt(2.0), 1e-6);
}

TEST_P(BothPlanners, TypedFailures) {
  Costmap m = wallMap();
  for (int y = 8; y < 10; ++y) m.setCost({5, y}, cost::kLethal);  // closes the gap
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  Plan plan = planner.makePlan(m, {2.5, 2.5}, {8.5, 2.5});
  EXPECT_EQ(plan.status, PlanStatus::kNoPath);
  EXPECT_FALSE(plan.message.empty());
  EXPECT_TRUE(plan.path.empty());
  EXPECT_EQ(planner.makePlan(m, {5.5, 2.5}, {8.5, 2.5}).status, PlanStatus::kStartOccupied);
  EXPECT_EQ(planner.makePlan(m, {2.5, 2.5}, {5.5, 2.5}).status, PlanStatus::kGoalOccupied);
  EXPECT_EQ(planner.makePlan(m, {2.5, 2.5}, {15.0, 2.5}).status, PlanStatus::kGoalOffMap);
  EXPECT_EQ(planner.makePlan(m, {-1.0, 2.5}, {1.5, 2.5}).status, PlanStatus::kStartOffMap);
}

TEST_P(BothPlanners, GoalInAWallMovesWithinTheTolerance) {
  const Costmap m = wallMap();
  PlannerParams p;
  p.use_astar = GetParam();
  p.default_tolerance = 1.0;
  GlobalPlanner planner(p);
  const Plan plan = planner.makePlan(m, {2.5, 2.5}, {5.5, 2.5});
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_NEAR(plan.goal.x(), 4.5, 1e-9);  // the nearest free cell (the one on the start's side ties with 6.5; first wins)
  EXPECT_NEAR(plan.goal.y(), 2.5, 1e-9);
}

TEST_P(BothPlanners, UnknownSpaceOnlyWhenAllowed) {
  Costmap m(10, 3, 1.0, {0, 0});
  for (int y = 0; y < 3; ++y) m.setCost({5, y}, cost::kNoInformation);
  PlannerParams p;
  p.use_astar = GetParam();
  EXPECT_EQ(GlobalPlanner(p).makePlan(m, {1.5, 1.5}, {8.5, 1.5}).status, PlanStatus::kOk);
  p.allow_unknown = false;
  EXPECT_EQ(GlobalPlanner(p).makePlan(m, {1.5, 1.5}, {8.5, 1.5}).status, PlanStatus::kNoPath);
}

TEST_P(BothPlanners, PrefersLowCostCells) {
  // Two corridors: a short one through inflated cells (cost 200) and a longer free one.
  Costmap m(21, 7, 1.0, {0, 0}, cost::kLethal);
  for (int x = 0; x < 21; ++x) m.setCost({x, 1}, 200);   // short, expensive: 50 + 160 per cell
  for (int x = 0; x < 21; ++x) m.setCost({x, 5}, 0);     // free, 8 cells longer round trip
  for (int y = 1; y <= 5; ++y) {
    m.setCost({0, y}, 0);
    m.setCost({20, y}, 0);
  }
  PlannerParams p;
  p.use_astar = GetParam();
  const Plan plan = GlobalPlanner(p).makePlan(m, {0.5, 1.5}, {20.5, 1.5});
  ASSERT_EQ(plan.status, PlanStatus::kOk);
  bool used_free = false;
  for (const auto& q : plan.path) used_free = used_free || q.y() > 5.0;
  EXPECT_TRUE(used_free);
}

INSTANTIATE_TEST_SUITE_P(DijkstraAndAStar, BothPlanners, ::testing::Values(false, true));
