#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/world2d.h"

using mbot::core::Polygon;
using mbot::core::World2D;

namespace {
World2D squareRoom() {
  World2D w(0.5);
  // A 4 m x 4 m room centred at the origin, walls 0.1 m thick (inner faces at +-2).
  w.addBox({0, 2.05}, 0, 4.2, 0.1);
  w.addBox({0, -2.05}, 0, 4.2, 0.1);
  w.addBox({2.05, 0}, 0, 0.1, 4.2);
  w.addBox({-2.05, 0}, 0, 0.1, 4.2);
  return w;
}
Polygon square(double cx, double cy, double half) {
  return {{cx - half, cy - half}, {cx + half, cy - half}, {cx + half, cy + half}, {cx - half, cy + half}};
}
}  // namespace

TEST(World2D, RayDistancesToKnownWalls) {
  const World2D w = squareRoom();
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 2.0, 1e-12);
  EXPECT_NEAR(w.castRay({0.5, -1.0}, M_PI / 2, 10.0), 3.0, 1e-12);
  EXPECT_NEAR(w.castRay({0, 0}, M_PI / 4, 10.0), 2.0 * std::sqrt(2.0), 1e-9);  // exactly into the corner
  EXPECT_TRUE(std::isinf(w.castRay({0, 0}, 0.0, 1.5)));                          // beyond max range
  EXPECT_NEAR(w.castRay({5, 0}, M_PI, 10.0), 2.9, 1e-12);                        // from outside: outer face
}

TEST(World2D, BucketWalkAgreesWithBruteForce) {
  // The same clutter in three worlds: one bucket (every shape tested on every ray), default and fine.
  World2D brute(100.0), normal(0.5), fine(0.1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-1.9, 1.9), size(0.1, 0.6), ang(-M_PI, M_PI);
  for (World2D* w : {&brute, &normal, &fine}) {
    w->addBox({0, 2.05}, 0, 4.2, 0.1);
    w->addBox({0, -2.05}, 0, 4.2, 0.1);
    w->addBox({2.05, 0}, 0, 0.1, 4.2);
    w->addBox({-2.05, 0}, 0, 0.1, 4.2);
    w->addCylinder({0.3, -0.7}, 0.2);
  }
  for (int i = 0; i < 15; ++i) {
    const double x = pos(rng), y = pos(rng), sx = size(rng), sy = size(rng), yaw = ang(rng);
    for (World2D* w : {&brute, &normal, &fine}) w->addBox({x, y}, yaw, sx, sy);
  }
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d o(pos(rng), pos(rng));
    const double a = ang(rng);
    const double r = brute.castRay(o, a, 8.0);
    EXPECT_TRUE(std::isfinite(r));  // closed room: every ray returns
    EXPECT_DOUBLE_EQ(r, normal.castRay(o, a, 8.0));
    EXPECT_DOUBLE_EQ(r, fine.castRay(o, a, 8.0));
  }
}

TEST(World2D, NoBeamSeesThroughACorner) {
  // Two walls meeting at a corner: a ray aimed exactly at the shared corner point must stop there.
  World2D w;
  w.addSegment({1, -1}, {1, 1});
  w.addSegment({1, 1}, {-1, 1});
  for (double a = 0.0; a < M_PI / 2 + 1e-9; a += M_PI / 720) {
    EXPECT_TRUE(std::isfinite(w.castRay({0, 0}, a, 5.0))) << a;
  }
  EXPECT_NEAR(w.castRay({0, 0}, M_PI / 4, 5.0), std::sqrt(2.0), 1e-9);
}

TEST(World2D, CylinderAndDynamicPolygons) {
  World2D w;
  w.addCylinder({3, 0}, 0.5);
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 2.5, 1e-12);
  EXPECT_TRUE(std::isinf(w.castRay({0, 0}, M_PI / 2, 10.0)));
  w.setDynamicPolygons({square(0, 0, 0.2), square(1, 0, 0.1)});
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0, /*skip_dynamic=*/0), 0.9, 1e-12);  // own body skipped
  EXPECT_TRUE(w.overlaps(square(1.1, 0, 0.05), 0));
  EXPECT_FALSE(w.overlaps(square(1.5, 0.5, 0.05), 0));
}

TEST(World2D, DynamicCirclesAreSeenAndCollide) {
  // People: round moving obstacles, seen by rays and touched by footprints; replaced each step.
  World2D w = squareRoom();
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 2.0, 1e-12);
  w.setDynamicCircles({Eigen::Vector3d(1.0, 0.0, 0.25)});
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 0.75, 1e-12);
  EXPECT_TRUE(w.overlaps(square(0.7, 0, 0.1)));
  EXPECT_FALSE(w.overlaps(square(0.5, 0, 0.1)));
  w.setDynamicCircles({});
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 2.0, 1e-12);
  EXPECT_FALSE(w.overlaps(square(0.7, 0, 0.1)));
}

TEST(World2D, DistanceToDynamicPolygons) {
  World2D w;
  EXPECT_TRUE(std::isinf(w.distanceToDynamicPolygons({0, 0})));
  w.setDynamicPolygons({square(0, 0, 0.2), square(3, 0, 0.2)});
  EXPECT_DOUBLE_EQ(w.distanceToDynamicPolygons({0.1, 0.1}), 0.0);  // inside
  EXPECT_NEAR(w.distanceToDynamicPolygons({1.0, 0.0}), 0.8, 1e-12);
  EXPECT_NEAR(w.distanceToDynamicPolygons({2.0, 0.0}), 0.8, 1e-12);
  EXPECT_NEAR(mbot::core::pointPolygonDistance({0.5, 0.5}, square(0, 0, 0.2)), std::sqrt(0.18), 1e-12);
}

TEST(World2D, FootprintOverlap) {
  const World2D w = squareRoom();
  EXPECT_FALSE(w.overlaps(square(0, 0, 0.2)));
  EXPECT_TRUE(w.overlaps(square(1.85, 0, 0.2)));   // edge crosses the east wall
  EXPECT_TRUE(w.overlaps(square(2.05, 0, 0.02)));  // wholly inside the wall
  World2D furniture;
  furniture.addBox({0, 0}, 0, 0.1, 0.1);
  EXPECT_TRUE(furniture.overlaps(square(0, 0, 1.0)));  // small box wholly under the robot
  World2D plant;
  plant.addCylinder({0.5, 0}, 0.2);
  EXPECT_TRUE(plant.overlaps(square(0, 0, 0.35)));
  EXPECT_FALSE(plant.overlaps(square(0, 0, 0.25)));
}

TEST(World2D, ScanFollowsRep117AndIsSeeded) {
  const World2D w = squareRoom();
  std::mt19937 a(5), b(5);
  std::vector<float> s1(360), s2(360), exact(360);
  w.castScan({0, 0, 0}, -M_PI, M_PI / 180, 360, 0.1, 2.5, 0.01, 0.0, a, s1.data());
  w.castScan({0, 0, 0}, -M_PI, M_PI / 180, 360, 0.1, 2.5, 0.01, 0.0, b, s2.data());
  EXPECT_EQ(s1, s2);
  w.castScan({0, 0, 0}, -M_PI, M_PI / 180, 360, 0.1, 2.5, 0.0, 0.0, a, exact.data());
  EXPECT_NEAR(exact[180], 2.0, 1e-6);  // beam 180 looks along +x
  EXPECT_TRUE(std::isinf(exact[180 + 45]) && exact[180 + 45] > 0);  // corner at 2.83 m > range_max
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int i = 0; i < 360; ++i) {
    if (std::isfinite(s1[i])) {
      sum += s1[i] - exact[i];
      sum2 += (s1[i] - exact[i]) * (s1[i] - exact[i]);
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.0, 0.004);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.01, 0.003);
  std::vector<float> close(1);
  w.castScan({1.95, 0, 0}, 0, 0, 1, 0.1, 2.5, 0.0, 0.0, a, close.data());
  EXPECT_TRUE(std::isinf(close[0]) && close[0] < 0);  // closer than range_min
}

TEST(World2D, HeightsDecideWhatTheLaserSeesAndWhatStopsTheRobot) {
  using mbot::core::HeightRange;
  World2D w;
  w.addBox({2.05, 0}, 0, 0.1, 1.0, {2.0, 2.2});       // a lintel over a door: from 2 m up
  w.addBox({0, 2.05}, 0, 1.0, 0.1, {0.0, 0.05});      // a skirting 5 cm high: below the laser plane
  w.addCylinder({-2.0, 0}, 0.3, {0.7, 0.74});         // a table top above the robot
  w.addBox({0, -2.05}, 0, 1.0, 0.1, {-0.1, 0.0});     // a floor tile: its top is the floor
  const double laser_z = 0.2;
  EXPECT_TRUE(std::isinf(w.castRay({0, 0}, 0.0, 10.0, -1, laser_z)));       // under the lintel
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0), 2.0, 1e-12);                    // no height: every shape
  EXPECT_NEAR(w.castRay({0, 0}, 0.0, 10.0, -1, 2.1), 2.0, 1e-12);           // a laser at 2.1 m sees it
  EXPECT_TRUE(std::isinf(w.castRay({0, 0}, M_PI / 2, 10.0, -1, laser_z)));  // over the skirting
  EXPECT_TRUE(std::isinf(w.castRay({0, 0}, M_PI, 10.0, -1, laser_z)));      // under the table
  const HeightRange body{0.01, 0.4};
  EXPECT_FALSE(w.overlaps(square(2.0, 0, 0.2), -1, body));   // drives under the lintel
  EXPECT_TRUE(w.overlaps(square(0, 2.0, 0.2), -1, body));    // the skirting stops it
  EXPECT_FALSE(w.overlaps(square(-2.0, 0, 0.2), -1, body));  // under the table
  EXPECT_FALSE(w.overlaps(square(0, -2.0, 0.2), -1, body));  // over the tile
  EXPECT_TRUE(w.overlaps(square(2.0, 0, 0.2)));              // no body given: every shape
}

namespace {
// A 10 x 10 cell raster at 0.1 m whose cells (5..9, 4) form a wall.
mbot::core::GridShape wallGrid(const Eigen::Vector2d& origin, double yaw) {
  mbot::core::GridShape g;
  g.origin = origin;
  g.yaw = yaw;
  g.resolution = 0.1;
  g.width = g.height = 10;
  g.cells.assign(100, 0);
  for (int col = 5; col < 10; ++col) g.cells[4 * 10 + col] = 1;
  return g;
}
}  // namespace

TEST(World2D, GridRaysEnterTheFirstSolidCellExactly) {
  World2D w;
  w.addGrid(wallGrid({0, 0}, 0.0));
  // Up from (0.72, 0): the wall's row spans y in [0.4, 0.5).
  EXPECT_NEAR(w.castRay({0.72, 0.0}, M_PI / 2, 10.0), 0.4, 1e-9);
  EXPECT_NEAR(w.castRay({0.72, 1.5}, -M_PI / 2, 10.0), 1.0, 1e-9);  // from outside, down onto its top face
  EXPECT_TRUE(std::isinf(w.castRay({0.3, 0.0}, M_PI / 2, 10.0)));   // beside the wall
  EXPECT_NEAR(w.castRay({0.0, 0.45}, 0.0, 10.0), 0.5, 1e-9);        // along the row: its end face at x = 0.5
  EXPECT_NEAR(w.castRay({0.7, 0.45}, 0.0, 10.0), 0.0, 1e-9);        // starts inside
  EXPECT_TRUE(std::isinf(w.castRay({0.72, 0.0}, M_PI / 2, 0.3)));   // beyond max range
  // The same raster turned by 90 degrees about its origin: the wall now runs along -x... at x = -0.4.
  World2D turned;
  turned.addGrid(wallGrid({0, 0}, M_PI / 2));
  EXPECT_NEAR(turned.castRay({0.0, 0.72}, M_PI, 10.0), 0.4, 1e-9);
}

TEST(World2D, GridRaysAgreeWithTheSameCellsAsBoxes) {
  // Random solid cells, as a raster and as one box per cell: the same distances on random rays.
  std::mt19937 rng(5);
  std::bernoulli_distribution solid(0.08);
  mbot::core::GridShape g;
  g.origin = {-2.0, -1.5};
  g.yaw = 0.3;
  g.resolution = 0.1;
  g.width = 40;
  g.height = 30;
  World2D boxes, grid;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      const bool s = solid(rng);
      g.cells.push_back(s);
      if (!s) continue;
      const Eigen::Vector2d local((c + 0.5) * 0.1, (r + 0.5) * 0.1);
      const Eigen::Vector2d centre = g.origin + Eigen::Vector2d(std::cos(0.3) * local.x() - std::sin(0.3) * local.y(),
                                                                std::sin(0.3) * local.x() + std::cos(0.3) * local.y());
      boxes.addBox(centre, 0.3, 0.1, 0.1);
    }
  }
  grid.addGrid(g);
  std::uniform_real_distribution<double> pos(-3.0, 3.0), ang(-M_PI, M_PI);
  int compared = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d o(pos(rng), pos(rng));
    if (boxes.overlaps(square(o.x(), o.y(), 1e-3))) continue;
    const double a = ang(rng);
    const double b = boxes.castRay(o, a, 8.0), q = grid.castRay(o, a, 8.0);
    if (std::isinf(b)) {
      EXPECT_TRUE(std::isinf(q)) << "ray " << i;
    } else {
      EXPECT_NEAR(q, b, 1e-6) << "ray " << i;
      ++compared;
    }
    const Polygon foot = square(o.x(), o.y(), 0.17);
    EXPECT_EQ(grid.overlaps(foot), boxes.overlaps(foot)) << "footprint " << i;
  }
  EXPECT_GT(compared, 500);  // most rays hit something
}

TEST(World2D, GridOfWrongSizeIsRefused) {
  World2D w;
  mbot::core::GridShape g;
  g.width = 3;
  g.height = 2;
  g.cells.assign(5, 1);
  EXPECT_THROW(w.addGrid(g), std::invalid_argument);
}
