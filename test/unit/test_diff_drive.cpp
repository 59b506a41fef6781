#include <cmath>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/diff_drive.h"

using mbot::core::DiffDrive;
using mbot::core::DiffDriveParams;
using mbot::core::Polygon;
using mbot::core::World2D;

namespace {
const Polygon kFootprint{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}};
void drive(DiffDrive& d, const World2D& w, double v, double wz, double seconds, double& now, int& hits) {
  for (int i = 0; i < static_cast<int>(std::round(seconds / 0.01)); ++i) {
    d.command(v, wz, now);
    hits += d.step(0.01, now, w);
    now += 0.01;
  }
}
}  // namespace

TEST(DiffDrive, DrivesStraightAndTurnsExactly) {
  World2D empty;
  DiffDrive d(DiffDriveParams(), kFootprint, {1.0, 2.0, M_PI / 2}, 1);
  double now = 0;
  int hits = 0;
  drive(d, empty, 0.5, 0.0, 2.0, now, hits);
  EXPECT_NEAR(d.pose().x(), 1.0, 1e-9);
  EXPECT_NEAR(d.pose().y(), 3.0, 1e-9);
  drive(d, empty, 0.0, M_PI / 2, 1.0, now, hits);
  EXPECT_NEAR(d.pose().z(), M_PI, 1e-9);
  EXPECT_EQ(hits, 0);
  // Without slip noise, odometry is the motion since spawn, expressed in the odom frame.
  EXPECT_NEAR(d.odomPose().x(), 1.0, 1e-9);
  EXPECT_NEAR(d.odomPose().y(), 0.0, 1e-9);
}

TEST(DiffDrive, AccelerationLimitAndCommandTimeout) {
  World2D empty;
  DiffDriveParams p;
  p.wheel_acceleration_mps2 = 1.0;
  p.cmd_timeout_s = 0.5;
  DiffDrive d(p, kFootprint, {0, 0, 0}, 1);
  d.command(1.0, 0.0, 0.0);
  for (int i = 0; i < 30; ++i) d.step(0.01, i * 0.01, empty);
  EXPECT_NEAR(d.linearVelocity(), 0.3, 1e-9);  // 1 m/s^2 for 0.3 s
  for (int i = 30; i < 150; ++i) d.step(0.01, i * 0.01, empty);  // no new command after t = 0
  EXPECT_NEAR(d.linearVelocity(), 0.0, 1e-9);
  EXPECT_FALSE(d.command(std::nan(""), 0.0, 1.5));
}

TEST(DiffDrive, CollisionStopsAtTheWallNeverThrough) {
  World2D w;
  w.addBox({2.05, 0}, 0, 0.1, 4.0);  // wall face at x = 2.0
  DiffDrive d(DiffDriveParams(), kFootprint, {0, 0, 0}, 1);
  double now = 0;
  int hits = 0;
  drive(d, w, 0.5, 0.0, 8.0, now, hits);
  EXPECT_GT(hits, 0);
  EXPECT_LE(d.pose().x() + 0.2, 2.0 + 1e-9);
  EXPECT_GT(d.pose().x() + 0.2, 2.0 - 0.01);  // stopped touching, not short of it
  int back_hits = 0;
  drive(d, w, -0.3, 0.0, 1.0, now, back_hits);  // backing away is allowed
  EXPECT_EQ(back_hits, 0);
  EXPECT_NEAR(d.pose().x(), 1.8 - 0.3, 0.01);
}

TEST(DiffDrive, SlipNoiseMakesOdometryDriftButNotTruth) {
  World2D empty;
  DiffDriveParams p;
  p.slip_stddev = 0.05;
  DiffDrive a(p, kFootprint, {0, 0, 0}, 7), b(p, kFootprint, {0, 0, 0}, 7);
  double now = 0, now_b = 0;
  int hits = 0;
  drive(a, empty, 0.4, 0.2, 10.0, now, hits);
  drive(b, empty, 0.4, 0.2, 10.0, now_b, hits);
  EXPECT_EQ(a.odomPose(), b.odomPose());  // seeded: repeatable
  const double err = (a.odomPose().head<2>() - a.pose().head<2>()).norm();
  EXPECT_GT(err, 1e-4);
  EXPECT_LT(err, 0.5);
  DiffDriveParams no_separation;
  no_separation.wheel_separation_m = 0.0;
  EXPECT_THROW(DiffDrive(no_separation, kFootprint, {0, 0, 0}, 1), std::invalid_argument);
}
