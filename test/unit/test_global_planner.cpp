#include <cmath>
#include <algorithm>
#include <cstdlib>
#include <stdexcept>

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

TEST_P(BothPlanners, AStartInAnInscribedPocketLeavesItButNeverCrossesAWall) {
  // A robot the costmap puts against a wall end (its centre inscribed, every neighbour inscribed):
  // navfn clears only the robot's cell and finds no way out; here the inscribed cells within
  // kStartEscape_m of the start are passable, lethal ones never.
  Costmap m(60, 60, 0.05, {0, 0});
  for (int y = 0; y < 60; ++y) m.setCost({30, y}, cost::kLethal);                 // wall at x = 1.5 m
  for (int y = 0; y < 60; ++y)
    for (int x = 26; x <= 34; ++x)
      if (x != 30) m.setCost({x, y}, cost::kInscribed);                            // its inscribed band
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Plan out = planner.makePlan(m, {1.42, 1.5}, {0.5, 1.5});  // start inscribed, 0.07 m from the wall
  ASSERT_EQ(out.status, PlanStatus::kOk) << out.message;
  for (const auto& q : out.path) EXPECT_LT(q.x(), 1.5) << "crossed the wall";
  // Away from the start the inscribed band still blocks: no goal inside it far along the wall.
  const Plan along = planner.makePlan(m, {0.5, 0.5}, {1.4, 2.9});
  EXPECT_NE(along.status, PlanStatus::kOk);
}

TEST_P(BothPlanners, CellsAtLethalCostOrAboveAreObstacles) {
  // global_planner's lethal_cost: a gap whose cells cost 230 is crossed at the default (253) and
  // avoided at 220 (move_base sets it to the costmap's contact cost).
  Costmap m(40, 20, 0.1, {0, 0});
  for (int y = 0; y < 20; ++y) m.setCost({20, y}, cost::kLethal);  // a wall at x = 2.0 m
  for (int y = 9; y <= 10; ++y) m.setCost({20, y}, 230);            // a gap in its middle
  m.setCost({20, 19}, 0);                                            // and a way round at the top
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  auto throughGap = [&](const Plan& plan) {
    for (const auto& q : plan.path) {
      const Cell c = m.worldToCell(q);
      if (c.x == 20 && (c.y == 9 || c.y == 10)) return true;
    }
    return false;
  };
  const Plan direct = planner.makePlan(m, {0.55, 0.95}, {3.55, 0.95});
  ASSERT_EQ(direct.status, PlanStatus::kOk) << direct.message;
  EXPECT_TRUE(throughGap(direct));
  planner.setLethalCost(220);
  const Plan around = planner.makePlan(m, {0.55, 0.95}, {3.55, 0.95});
  ASSERT_EQ(around.status, PlanStatus::kOk) << around.message;
  EXPECT_FALSE(throughGap(around));
  for (const auto& q : around.path) EXPECT_LT(m.cost(m.worldToCell(q)), 220);
  EXPECT_THROW(planner.setLethalCost(0), std::invalid_argument);
  EXPECT_THROW(planner.setLethalCost(254), std::invalid_argument);
}

TEST_P(BothPlanners, ARoomyWayIsTakenOnlyWhenItIsNotMuchLonger) {
  // A wall at x = 2.0 m with a tight gap (cost 230) on the straight line and a roomy way round its
  // end. Roomy threshold 220, contact threshold 253: the way round is taken when it is at most
  // max_detour_m longer than the way through the gap, the gap otherwise.
  auto world = [](int wall_to_y) {
    Costmap m(40, 60, 0.1, {0, 0});
    for (int y = 0; y < wall_to_y; ++y) m.setCost({20, y}, cost::kLethal);
    m.setCost({20, 5}, 230);  // the gap, on the line y = 0.55
    return m;
  };
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Eigen::Vector2d start(0.55, 0.55), goal(3.55, 0.55);
  auto throughGap = [](const Costmap& m, const Plan& plan) {
    for (const auto& q : plan.path) {
      if (m.worldToCell(q) == Cell{20, 5}) return true;
    }
    return false;
  };
  int used = 0;
  // The wall ends at y = 3.0 m: round it is about 3 m longer than through the gap.
  const Costmap short_wall = world(30);
  Plan plan = planPreferringRoom(planner, short_wall, start, goal, 220, cost::kInscribed, 4.0, &used);
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_FALSE(throughGap(short_wall, plan)) << "a detour within max_detour_m keeps room";
  EXPECT_EQ(used, 220);
  plan = planPreferringRoom(planner, short_wall, start, goal, 220, cost::kInscribed, 2.0, &used);
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_TRUE(throughGap(short_wall, plan)) << "a detour beyond max_detour_m is not worth the room";
  EXPECT_EQ(used, cost::kInscribed);
  EXPECT_LT(pathLength(plan.path), 3.5);
  // No way round: the gap, whatever the detour allowed.
  const Costmap closed = world(60);
  plan = planPreferringRoom(planner, closed, start, goal, 220, cost::kInscribed, 100.0, &used);
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_TRUE(throughGap(closed, plan));
  EXPECT_EQ(used, cost::kInscribed);
  // Nothing tight on an open floor: the roomy way.
  const Costmap open(40, 60, 0.1, {0, 0});
  plan = planPreferringRoom(planner, open, start, goal, 220, cost::kInscribed, 0.5, &used);
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_EQ(used, 220);
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

namespace {
// Rooms of `room` cells with one-cell walls and a `door`-cell door in each wall at a seeded place,
// inflated as the costmap would be (lethal walls, a cost falling off over 6 cells).
Costmap maze(int n, int room, int door, unsigned seed) {
  Costmap m(n, n, 0.05, {0, 0});
  std::srand(seed);
  for (int k = 0; k < n; k += room) {
    for (int j = 0; j < n; ++j) {
      m.setCost({j, k}, cost::kLethal);
      m.setCost({k, j}, cost::kLethal);
    }
    for (int j = 0; j + room <= n; j += room) {
      const int a = j + 3 + std::rand() % (room - door - 6), b = j + 3 + std::rand() % (room - door - 6);
      for (int d = 0; d < door; ++d) {
        m.setCost({a + d, k}, cost::kFree);
        m.setCost({k, b + d}, cost::kFree);
      }
    }
  }
  Costmap inflated = m;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      if (m.cost({x, y}) != cost::kLethal) continue;
      for (int dy = -6; dy <= 6; ++dy) {
        for (int dx = -6; dx <= 6; ++dx) {
          const Cell c{x + dx, y + dy};
          if (!m.contains(c) || m.cost(c) == cost::kLethal) continue;
          const double d = std::hypot(dx, dy);
          const uint8_t v = d <= 2.0 ? cost::kInscribed : d <= 6.0 ? static_cast<uint8_t>(252 * std::exp(-0.5 * (d - 2))) : 0;
          if (v > inflated.cost(c)) inflated.setCost(c, v);
        }
      }
    }
  }
  return inflated;
}
}  // namespace

// The hierarchical search (coarse blocks, then a corridor) against the whole-map search of before:
// the same path length within 2% on random start / goal pairs in a maze, never through an obstacle.
TEST_P(BothPlanners, HierarchicalPlansMatchTheWholeMapSearch) {
  const Costmap m = maze(240, 40, 8, 7);
  PlannerParams fast, reference;
  fast.use_astar = reference.use_astar = GetParam();
  reference.use_bounds = false;
  GlobalPlanner a(fast), b(reference);
  std::srand(11);
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector2d s(0.05 * (std::rand() % 240), 0.05 * (std::rand() % 240));
    const Eigen::Vector2d g(0.05 * (std::rand() % 240), 0.05 * (std::rand() % 240));
    const Plan pa = a.makePlan(m, s, g), pb = b.makePlan(m, s, g);
    ASSERT_EQ(pa.status, pb.status) << "trial " << trial << ": " << pa.message << " / " << pb.message;
    if (pa.status != PlanStatus::kOk) continue;
    ++compared;
    // Inscribed cells are passable near an inscribed start only (kStartEscape_m); lethal ones never.
    std::vector<Eigen::Vector2d> beyond;
    for (const auto& q : pa.path) {
      if (m.cost(m.worldToCell(q)) == cost::kLethal || (q - s).norm() > GlobalPlanner::kStartEscape_m + 0.05) beyond.push_back(q);
    }
    EXPECT_FALSE(touchesObstacle(m, beyond))
        << "trial " << trial << " from " << s.transpose() << " (cost " << int(m.cost(m.worldToCell(s))) << ") to " << g.transpose()
        << "; the reference " << (touchesObstacle(m, {pb.path.begin() + 1, pb.path.end()}) ? "too" : "not");
    EXPECT_LE(pathLength(pa.path), 1.02 * pathLength(pb.path) + 1e-9) << "trial " << trial << " from " << s.transpose() << " to " << g.transpose();
  }
  EXPECT_GE(compared, 20);
}

// A wall one cell thick inside blocks is invisible to the coarse level; the corridor then holds no
// path and the search widens until it finds the way round.
TEST_P(BothPlanners, ThinWallsTheCoarseLevelMissesAreStillAvoided) {
  Costmap m(200, 60, 0.05, {0, 0});
  for (int y = 0; y < 58; ++y) m.setCost({101, y}, cost::kLethal);  // a gap only at the top
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Plan plan = planner.makePlan(m, {1.0, 0.5}, {9.0, 0.5});
  ASSERT_EQ(plan.status, PlanStatus::kOk) << plan.message;
  EXPECT_FALSE(touchesObstacle(m, plan.path));
  double top = 0.0;
  for (const auto& q : plan.path) top = std::max(top, q.y());
  EXPECT_GT(top, 58 * 0.05);
}

// A goal in a closed room: the coarse level proves there is no path without flooding the map.
TEST_P(BothPlanners, NoPathIsFoundWithoutSearchingTheWholeMap) {
  Costmap m(400, 400, 0.05, {0, 0});
  for (int k = 300; k < 340; ++k) {
    for (int t : {300, 339}) {
      for (int d = -4; d <= 4; ++d) {  // walls 9 cells thick, as inflation makes them
        m.setCost({k, t + d}, cost::kLethal);
        m.setCost({t + d, k}, cost::kLethal);
      }
    }
  }
  PlannerParams p;
  p.use_astar = GetParam();
  GlobalPlanner planner(p);
  const Plan plan = planner.makePlan(m, {1.0, 1.0}, {16.0, 16.0});
  EXPECT_EQ(plan.status, PlanStatus::kNoPath);
  EXPECT_EQ(plan.expanded, 0);
}
