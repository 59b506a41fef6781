#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/inflation_layer.h"
#include "mbot_slam_navigation/core/local_planner.h"
#include "mbot_slam_navigation/core/obstacle_layer.h"
#include "mbot_slam_navigation/core/pose2d.h"
#include "tutorial_planner_params.h"

using namespace mbot::core;
using mbot::core::test_fixtures::tutorialParams;

namespace {
// The four-wheel car's footprint from the tutorial's costmap_common_params.yaml.
Footprint square() { return {{-0.2, -0.2}, {-0.2, 0.2}, {0.2, 0.2}, {0.2, -0.2}}; }

std::vector<Eigen::Vector2d> straightPlan(Eigen::Vector2d from, Eigen::Vector2d to, double step = 0.05) {
  std::vector<Eigen::Vector2d> plan;
  const double d = (to - from).norm();
  for (double s = 0; s <= d + 1e-9; s += step) plan.push_back(from + (to - from) * (s / d));
  return plan;
}

Costmap inflated(Costmap m) {
  InflationParams ip;
  ip.inscribed_radius = 0.2;
  ip.inflation_radius = 0.6;
  inflate(m, ip);
  return m;
}
}  // namespace

TEST(DistanceGrid, CountsFourConnectedStepsAroundObstacles) {
  Costmap m(10, 10, 1.0, {0, 0});
  for (int y = 0; y < 9; ++y) m.setCost({5, y}, cost::kLethal);
  DistanceGrid g;
  g.reset(m);
  ASSERT_TRUE(g.setLocalGoal(m, {{8.5, 0.5}}));
  EXPECT_EQ(g.at({8, 0}), 0.0);
  EXPECT_EQ(g.at({8, 3}), 3.0);
  // From (4, 0) the only way is over the wall's end at y = 9: 9 up, 4 across, 9 down.
  EXPECT_EQ(g.at({4, 0}), 9.0 + 4.0 + 9.0);
  EXPECT_EQ(g.at({5, 0}), g.obstacle());
}

TEST(DistanceGrid, UnknownPlanPointsAreNoTarget) {
  Costmap m(10, 10, 1.0, {0, 0}, cost::kNoInformation);
  DistanceGrid g;
  g.reset(m);
  EXPECT_FALSE(g.setPath(m, {{1.5, 1.5}, {2.5, 1.5}}));
}

TEST(Densify, InsertsPointsAtMostOneResolutionApart) {
  const auto d = densifyPlan({{0, 0}, {1, 0}}, 0.1);
  ASSERT_GE(d.size(), 11u);
  for (std::size_t i = 1; i < d.size(); ++i) EXPECT_LE((d[i] - d[i - 1]).norm(), 0.1 + 1e-9);
}

TEST(FootprintCells, CoverTheInteriorOfTheSquare) {
  Costmap m(40, 40, 0.05, {0, 0});
  const auto cells = footprintCells(m, {1.0, 1.0, 0.0}, square());
  // 0.4 m square: 8 x 8 cells plus the outline cells on the far edges (9 x 9 at most).
  EXPECT_GE(cells.size(), 64u);
  EXPECT_LE(cells.size(), 81u);
}

TEST(LocalPlanner, DrivesStraightAlongAStraightPlanAtTheSpeedLimit) {
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({1.0, 2.5}, {4.5, 2.5}));
  const Trajectory t = lp.findBestPath(m, {1.0, 2.5, 0.0}, {0.3, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  // ROS scores a trajectory at its last simulated point, one step short of its end, so neighbouring
  // speeds tie or swap by a cell; the choice is near the top speed, straight ahead.
  EXPECT_GT(t.xv, 0.8 * 0.3);
  EXPECT_NEAR(t.thetav, 0.0, 1e-9);
}

TEST(LocalPlanner, TurnsTowardsAPlanToTheLeft) {
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.5, 2.5}, {2.5, 4.5}));  // the plan leaves to +y, the robot faces +x
  const Trajectory t = lp.findBestPath(m, {2.5, 2.5, 0.0}, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_GT(t.thetav, 0.0);
}

TEST(LocalPlanner, SlowsDownNearTheGoal) {
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.0, 2.5}, {2.2, 2.5}));
  const Trajectory t = lp.findBestPath(m, {2.0, 2.5, 0.0}, {0.3, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  // max_vel_x is capped at distance / sim_time = 0.2 / 1.7.
  EXPECT_LE(t.xv, 0.2 / 1.7 + 1e-9);
}

TEST(LocalPlanner, NeverChoosesATrajectoryWhoseFootprintHitsAWall) {
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) raw.setCost({60, y}, cost::kLethal);  // a wall at x = 3.0 m
  const Costmap m = inflated(raw);
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.5, 2.5}, {4.5, 2.5}));  // a (bad) plan straight through the wall
  const Trajectory t = lp.findBestPath(m, {2.6, 2.5, 0.0}, {0.0, 0, 0});
  for (const auto& p : t.points) EXPECT_GE(footprintCost(m, p, square()), 0) << p.transpose();
  if (t.cost >= 0 && !t.points.empty()) EXPECT_LT(t.points.back().x() + 0.2, 3.0);
}

TEST(LocalPlanner, ACentreInAnInscribedCellCanStillTurnOrBackOut) {
  // A lethal cell 0.1 m ahead of the centre, inside the body (a thin obstacle seen under the robot):
  // the centre cell is inscribed, but the footprint's outline is clear, so the robot is not frozen.
  Costmap raw(100, 100, 0.05, {0, 0});
  raw.setCost(raw.worldToCell({2.62, 2.52}), cost::kLethal);
  const Costmap m = inflated(raw);
  const Eigen::Vector3d pose(2.52, 2.52, 0.0);
  ASSERT_EQ(m.cost(m.worldToCell(pose.head<2>())), cost::kInscribed);
  ASSERT_GE(footprintCost(m, pose, square()), 0);
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.52, 2.52}, {2.52, 0.5}));  // the way on is to the right
  const Trajectory t = lp.findBestPath(m, pose, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_TRUE(t.xv != 0.0 || t.thetav != 0.0);
}

TEST(LocalPlanner, ApproachesAGoalNearAWallInsteadOfSpinning) {
  // The goal is 0.375 m from a wall, inside its inflation: an in-place rotation scores as well as
  // the best forward move, and ROS's rule (a rotation wins a tie) would spin the robot there.
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int x = 0; x < 100; ++x) raw.setCost({x, 70}, cost::kLethal);  // wall at y = 3.5 m
  const Costmap m = inflated(raw);
  const Eigen::Vector3d pose(2.0, 2.6, 1.8);
  LocalPlanner lp(tutorialParams(), padFootprint(circleFootprint(0.2), 0.01));
  lp.setPlan(straightPlan({2.0, 2.6}, {2.8, 3.125}, 0.025));
  const Trajectory t = lp.findBestPath(m, pose, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  double spin = 1e9;
  for (double w : {-1.0, -0.5, 0.5, 1.0}) {
    const double c = lp.simulate(m, pose, {0, 0, 0}, {0, 0, w}).cost;
    if (c >= 0) spin = std::min(spin, c);
  }
  ASSERT_LE(spin, t.cost) << "not the situation where ROS's rule spins";
  // It faces 70 degrees off the plan: it may turn towards it first, but then it drives to the goal
  // (closed loop at 10 Hz, until within xy_goal_tolerance 0.1 m as move_base stops it), not spin on
  // the spot. (Before the occupancy weight was scaled by the resolution as ROS scales it, it stopped
  // 0.27 m short, where the wall's inflation outweighed the last steps.)
  Eigen::Vector3d p = pose, vel(0, 0, 0);
  double turned = 0.0;
  for (int k = 0; k < 150 && (p.head<2>() - Eigen::Vector2d(2.8, 3.125)).norm() > 0.1; ++k) {
    const Trajectory c = lp.findBestPath(m, p, vel);
    ASSERT_GE(c.cost, 0.0) << "no command at (" << p.x() << ", " << p.y() << ")";
    if (c.xv == 0.0) turned += std::abs(c.thetav / 10.0);
    p = integrateArc(p, c.xv / 10.0, c.thetav / 10.0);
    vel = {c.xv, 0, c.thetav};
  }
  EXPECT_LT((p.head<2>() - Eigen::Vector2d(2.8, 3.125)).norm(), 0.1)
      << "not at the goal (0.96 m away at the start) after 15 s: at (" << p.x() << ", " << p.y() << ")";
  EXPECT_LT(turned, M_PI / 2) << "turned " << turned << " rad on the spot to face a plan 70 degrees off";
}

TEST(LocalPlanner, FollowsAPlanThatRunsDiagonallyAwayFromTheGoalInsteadOfSpinning) {
  // Out of a doorway at 45 degrees: the plan runs south-east, then east, then north-east to the
  // local goal. Along the first leg the 4-connected goal distance stays the same (one cell nearer
  // in x, one farther in y) and the path distance is 0, so no move lowers their sum: the robot
  // spun on the spot for minutes in the simulated home (exploration rostest) until move_base's
  // back_up recovery happened to move it.
  const Costmap m(100, 100, 0.05, {0, 0});
  std::vector<Eigen::Vector2d> plan = straightPlan({1.0, 3.0}, {1.5, 2.5});
  for (const auto& leg : {straightPlan({1.5, 2.5}, {3.0, 2.5}), straightPlan({3.0, 2.5}, {4.0, 3.5})}) {
    plan.insert(plan.end(), leg.begin() + 1, leg.end());
  }
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(plan);
  Eigen::Vector3d pose(1.0, 3.0, -M_PI / 4), vel(0, 0, 0);
  const Trajectory first = lp.findBestPath(m, pose, vel);
  ASSERT_GE(first.cost, 0.0);
  EXPECT_GT(first.xv, 0.0) << "turned on the spot (vtheta " << first.thetav << ") instead of following the plan";
  // Closed loop at 3 Hz: it gets round the corner of the plan.
  for (int k = 0; k < 30; ++k) {
    const Trajectory t = lp.findBestPath(m, pose, vel);
    ASSERT_GE(t.cost, 0.0);
    pose = integrateArc(pose, t.xv / 3.0, t.thetav / 3.0);
    vel = {t.xv, 0, t.thetav};
  }
  EXPECT_GT(pose.x(), 1.8) << "stuck at (" << pose.x() << ", " << pose.y() << ")";
}

TEST(LocalPlanner, AFullTurnOnTheSpotWithoutProgressEndsInItsBestForwardMove) {
  // On the plan's last cell no move gets nearer the plan or the goal: it turns on the spot, and
  // after one full circle takes a forward move instead of turning for ever.
  const Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({1.025, 2.525}, {2.525, 2.525}));  // cell centres
  Eigen::Vector3d pose(2.525, 2.525, 0.3), vel(0, 0, 0);
  double turned = 0.0;
  int forward_at = -1;
  for (int k = 0; k < 60 && forward_at < 0; ++k) {
    const Trajectory t = lp.findBestPath(m, pose, vel);
    ASSERT_GE(t.cost, 0.0);
    if (t.xv > 0) forward_at = k;
    turned += std::abs(t.thetav) / 3.0;
    pose = integrateArc(pose, t.xv / 3.0, t.thetav / 3.0);
    vel = {t.xv, 0, t.thetav};
  }
  ASSERT_GE(forward_at, 0) << "still turning after " << turned << " rad";
  EXPECT_GE(turned, 2.0 * M_PI - 0.6) << "moved before a full turn showed no progress";
}

TEST(LocalPlanner, AFootprintAlreadyTouchingAWallMovesOutAndNeverDeeper) {
  // A person walked up, or a wall end's cells round onto the outline: the robot stands with its
  // outline on a lethal cell. Every trajectory with the full footprint is invalid, turning away
  // included; the planner must still find a way out, and only away from the wall.
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) raw.setCost({60, y}, cost::kLethal);  // wall cells x 3.00 .. 3.05
  const Costmap m = inflated(raw);
  const Footprint round = circleFootprint(0.2);
  const Eigen::Vector3d pose(2.82, 2.5, M_PI);  // outline reaches 3.02: on the wall's cells
  ASSERT_LT(footprintCost(m, pose, round), 0);
  LocalPlanner lp(tutorialParams(), round);
  lp.setPlan(straightPlan({2.82, 2.5}, {1.0, 2.5}));  // the way on is away from the wall
  const Trajectory t = lp.findBestPath(m, pose, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0) << "frozen against the wall";
  EXPECT_LT(lp.lastFootprintScale(), 1.0);
  ASSERT_FALSE(t.points.empty());
  EXPECT_LE(t.points.back().x(), pose.x() + 1e-9);  // never towards the wall
  // The same robot clear of the wall plans with its whole footprint.
  lp.findBestPath(m, {2.5, 2.5, M_PI}, {0, 0, 0});
  EXPECT_EQ(lp.lastFootprintScale(), 1.0);
}

TEST(LocalPlanner, APersonInsideTheFootprintIsNeverDrivenNearer) {
  // A person walked into the robot: lethal cells 0.12 m ahead of its centre, inside its 0.2 m
  // footprint, where every cell around costs the same (inscribed), so the centre cost cannot tell
  // nearer from farther. The plan runs on through the person: the robot must not follow it there,
  // but may back away or turn.
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int dy = -1; dy <= 1; ++dy) raw.setCost(raw.worldToCell({2.62, 2.5 + 0.05 * dy}), cost::kLethal);
  const Costmap m = inflated(raw);
  const Footprint round = circleFootprint(0.2);
  const Eigen::Vector3d pose(2.5, 2.5, 0.0);
  ASSERT_GE(footprintCost(m, pose, round), 0);  // the outline does not see it: it is inside
  LocalPlanner lp(tutorialParams(), round);
  lp.setPlan(straightPlan({2.5, 2.5}, {4.5, 2.5}));  // on east, through the person
  const Trajectory t = lp.findBestPath(m, pose, {0, 0, 0});
  EXPECT_NEAR(lp.lastObstacleInside(), 0.10, 1e-6);  // the near side of the cell at 2.60 .. 2.65
  if (t.cost >= 0.0) {
    for (const Eigen::Vector3d& q : t.points) {
      EXPECT_LE(q.x(), pose.x() + 1e-3) << "drove on into the person";
    }
  }
  // Scored one by one: forward is invalid, backing away is not.
  EXPECT_LT(lp.scoreTrajectory(m, pose, {0, 0, 0}, {0.3, 0.0, 0.0}), 0.0);
  EXPECT_LT(lp.scoreTrajectory(m, pose, {0, 0, 0}, {0.2, 0.0, 0.5}), 0.0);
  EXPECT_GE(lp.scoreTrajectory(m, pose, {0, 0, 0}, {0.0, 0.0, 1.0}), 0.0);  // turning keeps its distance
}

TEST(LocalPlanner, ALaserCoveredAllRoundStopsTheRobot) {
  // Every beam -inf (a person stands over the laser): marks at range_min all round. No shrunken
  // footprint is free, so no command: the robot waits until the person has gone.
  Costmap raw(100, 100, 0.05, {0, 0});
  ObservationSourceParams p;
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = 2 * M_PI / 360;
  s.range_min_m = 0.1;
  s.range_max_m = 5.0;
  s.ranges_m.assign(360, -std::numeric_limits<float>::infinity());
  updateWithScan(raw, {2.5, 2.5, 0.0}, s, p);
  const Costmap m = inflated(raw);
  LocalPlanner lp(tutorialParams(), circleFootprint(0.2));
  lp.setPlan(straightPlan({2.5, 2.5}, {4.5, 2.5}));
  const Trajectory t = lp.findBestPath(m, {2.5, 2.5, 0.0}, {0, 0, 0});
  EXPECT_LT(t.cost, 0.0);
  EXPECT_EQ(t.xv, 0.0);
  EXPECT_EQ(t.thetav, 0.0);
}

TEST(LocalPlanner, BoxedInGivesNoCommand) {
  Costmap m(100, 100, 0.05, {0, 0});
  // A 0.5 m box of lethal cells around a 0.4 m robot (x 2.30 .. 2.75 inside): no turn, no back-up,
  // no forward move.
  for (int i = 40; i <= 60; ++i) {
    m.setCost({i, 40}, cost::kLethal);
    m.setCost({i, 50}, cost::kLethal);
    m.setCost({40, i}, cost::kLethal);
  }
  for (int i = 40; i <= 50; ++i) {
    m.setCost({45, i}, cost::kLethal);
    m.setCost({55, i}, cost::kLethal);
  }
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.52, 2.26}, {4.5, 2.26}));
  const Eigen::Vector3d pose(2.52, 2.26, 0.0);
  ASSERT_GE(footprintCost(m, pose, square()), 0);  // boxed in, not touching
  const Trajectory t = lp.findBestPath(m, pose, {0, 0, 0});
  EXPECT_LT(t.cost, 0.0);
  EXPECT_EQ(t.xv, 0.0);
  EXPECT_EQ(t.thetav, 0.0);
}

TEST(LocalPlanner, DwaLimitsTheWindowToOneControlPeriod) {
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlannerParams p = tutorialParams();
  p.dwa = true;
  p.sim_period = 0.1;
  p.acc_lim_x = 0.5;  // from rest, one period allows at most 0.05 m/s more
  LocalPlanner lp(p, square());
  lp.setPlan(straightPlan({1.0, 2.5}, {4.5, 2.5}));
  const Trajectory t = lp.findBestPath(m, {1.0, 2.5, 0.0}, {0.0, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_LE(t.xv, 0.05 + 1e-9);
  p.dwa = false;  // trajectory rollout: the window is sim_time long, 0.5 * 1.7 > max_vel_x
  LocalPlanner rollout(p, square());
  rollout.setPlan(straightPlan({1.0, 2.5}, {4.5, 2.5}));
  EXPECT_NEAR(rollout.findBestPath(m, {1.0, 2.5, 0.0}, {0.0, 0, 0}).xv, 0.3, 1e-9);
}

TEST(LocalPlanner, ScoresWorseFartherFromThePath) {
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({1.0, 2.5}, {4.5, 2.5}));
  lp.updateGrids(m, {1.0, 2.5, 0.0});
  const double on = lp.scoreTrajectory(m, {1.0, 2.5, 0.0}, {0.3, 0, 0}, {0.3, 0, 0});
  const double off = lp.scoreTrajectory(m, {1.0, 2.5, 0.0}, {0.3, 0, 0}, {0.3, 0, 0.8});
  ASSERT_GE(on, 0.0);
  ASSERT_GE(off, 0.0);
  EXPECT_LT(on, off);
}

TEST(LocalPlannerParams, RejectsNonsense) {
  LocalPlannerParams p;
  p.sim_time = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = LocalPlannerParams();
  p.min_vel_x = 1.0;
  p.max_vel_x = 0.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// The cycle's shortcuts (a footprint over free cells costs 0; one over cells with no lethal or
// unknown cell is valid and its cost is only computed if the trajectory could win) choose exactly
// the command, and give exactly the cost, of scoring every footprint by its outline: random
// obstacles, a round and a square robot, moving and standing.
TEST(LocalPlanner, ShortcutsChooseExactlyAsTheFullFootprintWalk) {
  int compared = 0, valid = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::srand(seed);
    Costmap raw(100, 100, 0.05, {0, 0});
    for (int k = 0; k < 10 + 5 * static_cast<int>(seed); ++k) raw.setCost({std::rand() % 100, std::rand() % 100}, cost::kLethal);
    const Costmap m = inflated(raw);
    for (const Footprint& fp : {square(), padFootprint(circleFootprint(0.2), 0.01)}) {
      LocalPlanner fast(tutorialParams(), fp), reference(tutorialParams(), fp);
      reference.setShortcuts(false);
      const auto plan = straightPlan({1.0, 0.8 + 0.5 * seed}, {4.5, 4.0});
      fast.setPlan(plan);
      reference.setPlan(plan);
      for (int trial = 0; trial < 8; ++trial) {
        const Eigen::Vector3d pose(0.8 + 0.45 * trial, 0.8 + 0.5 * seed, 0.4 * trial - 1.0);
        const Eigen::Vector3d vel(0.05 * (trial % 3), 0.0, 0.2 * (trial % 2));
        const Trajectory a = fast.findBestPath(m, pose, vel), b = reference.findBestPath(m, pose, vel);
        EXPECT_EQ(a.xv, b.xv) << "seed " << seed << " trial " << trial;
        EXPECT_EQ(a.yv, b.yv) << "seed " << seed << " trial " << trial;
        EXPECT_EQ(a.thetav, b.thetav) << "seed " << seed << " trial " << trial;
        EXPECT_DOUBLE_EQ(a.cost, b.cost) << "seed " << seed << " trial " << trial;
        ++compared;
        valid += a.cost >= 0;
      }
    }
  }
  EXPECT_EQ(compared, 96);
  EXPECT_GE(valid, 40);
}

TEST(LocalPlanner, TurnsTowardsAPlanThatLeavesSidewaysInsteadOfCrawling) {
  // The plan leaves the robot at a right angle (a goal beside it, the way out of a doorway): slow
  // forward arcs end in the same cells and the straight one won the tie, so the robot crawled
  // sideways to its plan at min_vel_x (a fifth of an exploration's commands). It turns on the spot
  // first, then drives at speed.
  const Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), padFootprint(circleFootprint(0.2), 0.01));
  lp.setPlan(straightPlan({2.5, 2.5}, {2.5, 4.0}, 0.025));
  Eigen::Vector3d pose(2.5, 2.5, 0.0), vel(0, 0, 0);
  const Trajectory first = lp.findBestPath(m, pose, vel);
  ASSERT_GE(first.cost, 0.0);
  EXPECT_EQ(first.xv, 0.0) << "drove on (vx " << first.xv << ") facing 90 degrees off the plan";
  EXPECT_GT(first.thetav, 0.0) << "turned away from the plan";
  double t = 0.0;
  for (; t < 10.0 && pose.y() < 3.9; t += 0.1) {
    const Trajectory c = lp.findBestPath(m, pose, vel);
    ASSERT_GE(c.cost, 0.0);
    pose = integrateArc(pose, c.xv / 10.0, c.thetav / 10.0);
    vel = {c.xv, 0, c.thetav};
  }
  // 1.4 m at 0.3 m/s plus a quarter turn: under 8 s; crawling at 0.05 m/s it takes 28 s
  EXPECT_GE(pose.y(), 3.9) << "at (" << pose.x() << ", " << pose.y() << ") after " << t << " s";
  EXPECT_LT(t, 8.0);
}

TEST(LocalPlanner, MeterScoringScalesTheOccupancyWeightByTheResolutionAsRosDoes) {
  // TrajectoryPlanner::reconfigure (which ROS's dynamic_reconfigure server runs at start-up)
  // multiplies occdist_scale by the resolution under meter_scoring, as it does the two biases. The
  // same trajectory over cells of cost 100 instead of 0 costs occdist_scale * 0.05 * 100 = 0.05 more.
  Costmap free_map(100, 100, 0.05, {0, 0});
  Costmap costly(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) {
    for (int x = 0; x < 100; ++x) costly.setCost({x, y}, 100);
  }
  for (bool meter : {true, false}) {
    LocalPlannerParams params = tutorialParams();
    params.meter_scoring = meter;
    LocalPlanner lp(params, padFootprint(circleFootprint(0.2), 0.01));
    lp.setPlan(straightPlan({1.0, 2.5}, {4.5, 2.5}));
    const Eigen::Vector3d pose(1.0, 2.5, 0.0), vel(0.3, 0, 0), cmd(0.3, 0, 0);
    lp.updateGrids(free_map, pose);
    const double base = lp.scoreTrajectory(free_map, pose, vel, cmd);
    lp.updateGrids(costly, pose);
    const double more = lp.scoreTrajectory(costly, pose, vel, cmd);
    ASSERT_GE(base, 0.0);
    EXPECT_NEAR(more - base, meter ? 0.01 * 0.05 * 100 : 0.01 * 100, 1e-9) << "meter_scoring " << meter;
  }
}

TEST(LocalPlanner, APlanThroughAWallOnlyTheLocalCostmapSeesStillGivesACommand) {
  // The global plan runs through a wall the local costmap has just seen (the global costmap,
  // updated less often, has not yet). ROS measures the goal distance to the last plan point in the
  // local map, behind the wall: no cell the robot can reach has one, every trajectory is invalid,
  // and the robot stood while move_base made the same plan again every cycle. Here the local goal
  // is the last plan point the robot can reach, and it drives on until move_base replans.
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) raw.setCost({70, y}, cost::kLethal);  // a wall at x = 3.5 m, all across
  const Costmap m = inflated(raw);
  LocalPlanner lp(tutorialParams(), circleFootprint(0.2));
  lp.setPlan(straightPlan({1.0, 2.5}, {4.8, 2.5}));
  const Trajectory t = lp.findBestPath(m, {1.0, 2.5, 0.0}, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0) << "no command: the robot stands";
  EXPECT_GT(t.xv, 0.0);
  EXPECT_LE(lp.localGoal().x(), 3.5 - 0.2 + 1e-9) << "the local goal lies before the wall and its inscribed band";
}

TEST(LocalPlanner, FollowsAPlanThatTurnsBackAtSpeedNotTowardsItsFarEnd) {
  // The plan goes 2 m east, 1 m north and 2 m back west, round what the local costmap does not
  // show (costs the global planner weighed, a way it knows to be shut). ROS's local goal is the
  // plan's last point in the local costmap, 1 m north of the robot: every move east along the plan
  // is a move away from it, and the robot crept on at min_vel_x. The local goal lies at most 2 m
  // along the plan, and the robot drives east at speed.
  Costmap m(100, 100, 0.05, {0, 0});
  LocalPlanner lp(tutorialParams(), circleFootprint(0.2));
  std::vector<Eigen::Vector2d> plan = straightPlan({1.0, 2.0}, {3.0, 2.0});
  for (const auto& p : straightPlan({3.0, 2.05}, {3.0, 3.0})) plan.push_back(p);
  for (const auto& p : straightPlan({2.95, 3.0}, {1.0, 3.0})) plan.push_back(p);
  lp.setPlan(plan);
  const Trajectory t = lp.findBestPath(m, {1.0, 2.0, 0.0}, {0.05, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_GT(t.xv, 0.8 * 0.3);
  EXPECT_NEAR(lp.localGoal().x(), 3.0, 0.1);
  EXPECT_NEAR(lp.localGoal().y(), 2.0, 0.1);
}

TEST(LocalPlanner, FacingThePlanWithNoRoomAheadItBacksUpInsteadOfTurning) {
  // The robot stands facing its plan with an obstacle just beyond its footprint: no forward move
  // fits, every turn on the spot does (a round robot). ROS turns, and then may not turn back (its
  // oscillation flags): in clutter a full circle. Here it backs up along the way it faces.
  Costmap raw(100, 100, 0.05, {0, 0});
  for (int y = 45; y <= 55; ++y) raw.setCost({55, y}, cost::kLethal);  // cells x 2.75 .. 2.80, just ahead
  const Costmap m = inflated(raw);
  LocalPlanner lp(tutorialParams(), circleFootprint(0.2));
  lp.setPlan(straightPlan({2.52, 2.5}, {4.5, 2.5}));
  const Trajectory t = lp.findBestPath(m, {2.52, 2.5, 0.0}, {0, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_LT(t.xv, 0.0);
  EXPECT_EQ(t.thetav, 0.0);
  EXPECT_FALSE(lp.escaping()) << "escape mode would forbid driving on once there is room";
  // Turned away from the plan, the same robot turns towards it as before.
  const Trajectory turn = lp.findBestPath(m, {2.52, 2.5, 1.2}, {0, 0, 0});
  ASSERT_GE(turn.cost, 0.0);
  EXPECT_EQ(turn.xv, 0.0);
  EXPECT_LT(turn.thetav, 0.0);
}

TEST(LocalPlanner, ThroughAGapItClearsByCentimetresItDrivesSlowly) {
  // Two rows of posts whose faces the laser saw 0.45 m apart (boxes in their cells), the mbot's
  // 0.4 m square inside the gap facing through it: 2.5 cm a side, 1.5 cm past the boxes' margin.
  // At 0.3 m/s a command acts 3 cm late (kBoxLatency), more than that; at 0.1 m/s 1 cm, less.
  Costmap raw(100, 100, 0.05, {0, 0});
  raw.enableBoxes();
  for (int x = 50; x <= 53; ++x) {
    raw.setCost({x, 45}, cost::kLethal);  // face at y = 2.275 m, half-way up the cell
    raw.setBox(raw.index({x, 45}), cell_box::pack(0, 0, 254, 127));
    raw.setCost({x, 54}, cost::kLethal);  // face at y = 2.725 m
    raw.setBox(raw.index({x, 54}), cell_box::pack(0, 127, 254, 254));
  }
  InflationParams ip;
  ip.inscribed_radius = 0.2;
  ip.inflation_radius = 0.6;
  Costmap m = raw;
  inflateWindow(raw, m, {0, 0, 100, 100}, ip);
  refineNearBoxes(raw, m, {0, 0, 100, 100}, ip, 0.2);
  const Eigen::Vector3d pose(2.35, 2.5, 0.0);
  ASSERT_GE(footprintCost(m, pose, square()), 0) << "the footprint fits the gap";
  LocalPlanner lp(tutorialParams(), square());
  lp.setPlan(straightPlan({2.35, 2.5}, {4.0, 2.5}));
  EXPECT_LT(lp.scoreTrajectory(m, pose, {0.1, 0, 0}, {0.3, 0, 0}), 0.0) << "full speed through the gap";
  EXPECT_GE(lp.scoreTrajectory(m, pose, {0.1, 0, 0}, {0.1, 0, 0}), 0.0) << "slowly through the gap";
  const Trajectory t = lp.findBestPath(m, pose, {0.1, 0, 0});
  ASSERT_GE(t.cost, 0.0);
  EXPECT_GT(t.xv, 0.0);
  EXPECT_LE(t.xv, 0.15);
}
