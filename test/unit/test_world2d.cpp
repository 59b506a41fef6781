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
