// Tracking where the scan constrains some directions weakly: 40 m straight along one plain wall and
// along a plain corridor, the robot driven by the simulator's differential drive and seen by its
// laser (the mbot's: 360 beams, 0.1-6 m, 1 cm noise, 10 Hz at 0.3 m/s). The scan fixes the
// distance to the walls and the heading, never how far the robot went: that must come from
// odometry (the matches' prior in the directions the scan leaves open, graph_slam.h). The distance
// driven must come out within 0.5%, with exact odometry and with the simulator's wheel slip. The
// heading is held to 0.25 degree: each node is matched against the nodes before it, and that chain
// wanders by about 0.2 degree over the 40 m whatever odometry says (0.1 degree is the aim).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/diff_drive.h"
#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/pose2d.h"
#include "mbot_slam_navigation/core/world2d.h"
#include "mbot_laser.h"

using namespace mbot::core;

namespace {

constexpr double kSpeed = 0.3;      // [m/s] the tutorial's max_vel_x
constexpr double kScanPeriod = 0.1; // [s] the mbot's laser at 10 Hz
constexpr double kSimStep = 0.01;   // [s] the simulator's step
constexpr double kRun = 40.0;       // [m]

struct RunResult {
  double weakest_sigma_m = 0.0;    // the matches' standard deviation along the weakest direction, median
  double worst_heading_deg = 0.0;  // |tracked - true| heading, worst over the run
  double distance_error = 0.0;     // (tracked - true) / true distance from the start, at the end
  double worst_lateral_m = 0.0;    // |tracked - true| across the run's direction, worst
  double worst_odometry_heading_deg = 0.0;  // |odometry - true| heading, worst over the run
};

/// GraphSlam as explore.launch runs it in the simulated worlds; inline, so the run is deterministic.
GraphSlamParams exploreParams() {
  GraphSlamParams p;
  p.matcher.max_range = 6.0;
  p.matcher.max_urange = 6.0;
  p.keep_trimmed_scans = true;
  p.local_visible_side = true;
  p.background = false;
  return p;
}

/// The mbot as the simulator drives it, at `start` (world frame); odometry with the simulator's
/// wheel slip `slip`, or exact when it is 0.
DiffDrive mbotDrive(const Eigen::Vector3d& start, double slip, unsigned seed) {
  DiffDriveParams drive_params;
  drive_params.wheel_separation_m = 0.38;
  drive_params.wheel_diameter_m = 0.12;
  drive_params.wheel_acceleration_mps2 = 1.0;
  drive_params.slip_stddev = slip;
  drive_params.odometry_from_world = slip <= 0.0;
  const Polygon footprint = {{0.2, 0.2}, {-0.2, 0.2}, {-0.2, -0.2}, {0.2, -0.2}};
  return DiffDrive(drive_params, footprint, start, seed);
}

/// Drives `run_m` metres along +x from `start` (world frame) at kSpeed, scanning at 10 Hz.
RunResult driveStraight(const World2D& world, const Eigen::Vector3d& start, double slip, unsigned seed,
                        double run_m = kRun) {
  DiffDrive robot = mbotDrive(start, slip, seed);
  GraphSlam slam(exploreParams());
  std::mt19937 rng(seed);
  RunResult r;
  std::vector<double> weakest;
  double t = 0.0;
  const int steps_per_scan = static_cast<int>(std::lround(kScanPeriod / kSimStep));
  while (true) {  // until run_m is driven, or twice the time that takes (then a failure)
    const Eigen::Vector3d truth = relativePose(start, robot.pose());  // map = odom = the spawn pose
    slam.processScan(robot.odomPose(), test_fixtures::mbotScanAt(world, robot.pose(), rng), t);
    const Eigen::Vector3d est = slam.currentPose();
    if (t > 0.0) weakest.push_back(slam.trackingWeakestSigma());
    r.worst_heading_deg = std::max(r.worst_heading_deg, std::abs(normalizeAngle(est.z() - truth.z())) * 180.0 / M_PI);
    const Eigen::Vector3d odom = relativePose(start, robot.odomPose());
    r.worst_odometry_heading_deg =
        std::max(r.worst_odometry_heading_deg, std::abs(normalizeAngle(odom.z() - truth.z())) * 180.0 / M_PI);
    r.worst_lateral_m = std::max(r.worst_lateral_m, std::abs(est.y() - truth.y()));
    if (truth.x() >= run_m || t > 2.0 * run_m / kSpeed + 10.0) {
      if (truth.x() < run_m) ADD_FAILURE() << "the robot got " << truth.x() << " m of " << run_m << " m (blocked)";
      r.distance_error = (est.x() - truth.x()) / std::max(truth.x(), 1e-3);
      if (!weakest.empty()) {
        std::nth_element(weakest.begin(), weakest.begin() + weakest.size() / 2, weakest.end());
        r.weakest_sigma_m = weakest[weakest.size() / 2];
      }
      break;
    }
    for (int k = 0; k < steps_per_scan; ++k) {
      robot.command(kSpeed, 0.0, t);
      robot.step(kSimStep, t, world);
      t += kSimStep;
    }
  }
  return r;
}

/// One plain wall 60 m long, 1.2 m to the robot's left: the only thing in view.
World2D plainWall() {
  World2D w;
  w.addBox({25.0, 1.25}, 0.0, 60.0, 0.1);
  return w;
}

/// A plain corridor 2.5 m wide and 50 m long, closed at both ends; the robot starts 2 m from the
/// west end, 0.3 m off the centre line.
World2D plainCorridor() {
  World2D w;
  w.addBox({23.0, 1.25 + 0.05}, 0.0, 50.2, 0.1);
  w.addBox({23.0, -1.25 - 0.05}, 0.0, 50.2, 0.1);
  w.addBox({-2.05, 0.0}, 0.0, 0.1, 2.7);
  w.addBox({48.05, 0.0}, 0.0, 0.1, 2.7);
  return w;
}

void expectStraight(const RunResult& r, const char* what) {
  ::testing::Test::RecordProperty("worst_heading_deg", std::to_string(r.worst_heading_deg));
  ::testing::Test::RecordProperty("distance_error", std::to_string(r.distance_error));
  std::printf("%s: worst heading error %.3f deg, distance error %+.3f%%, worst lateral error %.3f m, "
              "weakest direction's sigma %.3f m (median)\n", what, r.worst_heading_deg, 100.0 * r.distance_error,
              r.worst_lateral_m, r.weakest_sigma_m);
  EXPECT_LT(r.worst_heading_deg, 0.25) << what << ": the tracked heading drifted";
  EXPECT_LT(std::abs(r.distance_error), 0.005) << what << ": the distance driven came out wrong";
  EXPECT_LT(r.worst_lateral_m, 0.1) << what << ": the tracked pose left the line driven";
  // The matches report the direction they leave open: 5-6 cm here, about 1 cm in a room
  // (RoomMatchesFixEveryDirection).
  EXPECT_GT(r.weakest_sigma_m, 0.03) << what << ": the weak direction was not reported";
}

}  // namespace

TEST(StraightRuns, AlongOnePlainWallWithExactOdometry) {
  const RunResult r = driveStraight(plainWall(), {0.0, 0.0, 0.0}, 0.0, 3);
  expectStraight(r, "one wall, exact odometry");
}

TEST(StraightRuns, AlongAPlainCorridorWithExactOdometry) {
  const RunResult r = driveStraight(plainCorridor(), {0.0, 0.3, 0.0}, 0.0, 4);
  expectStraight(r, "corridor, exact odometry");
}

TEST(StraightRuns, AlongOnePlainWallWithTheSimulatorsWheelSlip) {
  // The simulator's default slip (gazebo_sim ~odometry_slip_stddev): odometry's heading wanders by
  // about a degree over the run; the scan must hold it.
  const RunResult r = driveStraight(plainWall(), {0.0, 0.0, 0.0}, 0.02, 5);
  expectStraight(r, "one wall, wheel slip");
}

TEST(StraightRuns, AlongAPlainCorridorWithTheSimulatorsWheelSlip) {
  const RunResult r = driveStraight(plainCorridor(), {0.0, 0.3, 0.0}, 0.02, 6);
  expectStraight(r, "corridor, wheel slip");
}

TEST(StraightRuns, PastALonePillarTheTurnAroundItIsOdometrys) {
  // An open hall: the robot leaves a corner of it (where scans pin every direction and odometry
  // earns its record) past one pillar, with nothing else within the laser's 6 m. The pillar fixes
  // the distance and the bearing to it but not a turn around it (a step sideways with a turn),
  // which a match reads from the noise of a few returns. Scan by scan that turn must come from
  // odometry: the heading wandered by degrees, and the map with it, when the match decided it.
  World2D w;
  w.addBox({-1.05, 0.0}, 0.0, 0.1, 6.0);  // the hall's west wall, behind the start
  w.addBox({0.5, -2.55}, 0.0, 3.0, 0.1);  // and its south wall's first metres
  w.addCylinder({7.0, 1.0}, 0.3);
  for (unsigned seed : {11u, 12u, 13u}) {
    const RunResult r = driveStraight(w, {0.0, 0.0, 0.0}, 0.02, seed, 14.0);
    std::printf("lone pillar, wheel slip, seed %u: worst heading error %.3f deg (odometry's %.3f), distance error "
                "%+.3f%%, worst lateral error %.3f m\n", seed, r.worst_heading_deg, r.worst_odometry_heading_deg,
                100.0 * r.distance_error, r.worst_lateral_m);
    // Where the scan pins nothing the heading can be no better than odometry's (1-2 degrees over
    // these 14 m of slip); it must not be worse.
    EXPECT_LT(r.worst_heading_deg, r.worst_odometry_heading_deg + 0.25) << "seed " << seed
        << ": the turn around the pillar came from the match's noise";
    EXPECT_LT(std::abs(r.distance_error), 0.005) << "seed " << seed;
    EXPECT_LT(r.worst_lateral_m, 0.25) << "seed " << seed;
  }
}

TEST(StraightRuns, BackAtAPlainWallAPartialClosureMendsTheHeading) {
  // 12 m along one plain wall, then a loop through open space out of the laser's reach (8 m away
  // from the wall, 8 m back along it, 8 m towards it) and 6 m along the wall again. Odometry's
  // heading is biased (0.15 degree per metre driven), and blind the tracking has only odometry.
  // Back at the wall the scan matches what the first stretch mapped anywhere along it: no full
  // closure can be made, a partial one (the distance to the wall and the heading) can, and must
  // bring the heading back.
  const World2D w = plainWall();
  DiffDrive robot = mbotDrive({0.0, 0.0, 0.0}, 0.0, 21);
  GraphSlam slam(exploreParams());
  std::mt19937 rng(21);
  const double bias = 0.15 * M_PI / 180.0;  // [rad/m]
  // Legs: heading [rad] and length [m].
  const std::vector<std::pair<double, double>> legs = {
      {0.0, 12.0}, {-M_PI / 2, 8.0}, {-M_PI, 8.0}, {M_PI / 2, 8.0}, {0.0, 6.0}};
  Eigen::Vector3d odom = Eigen::Vector3d::Zero(), last = robot.pose(), leg_start = robot.pose();
  double t = 0.0, blind_heading = 0.0;
  std::size_t leg = 0;
  bool turning = false;
  const int steps_per_scan = static_cast<int>(std::lround(kScanPeriod / kSimStep));
  while (leg < legs.size() && t < 600.0) {
    const Eigen::Vector3d step = relativePose(last, robot.pose());
    last = robot.pose();
    odom = composePose(odom, Eigen::Vector3d(step.x(), step.y(), step.z() + bias * std::abs(step.x())));
    slam.processScan(odom, test_fixtures::mbotScanAt(w, robot.pose(), rng), t);
    const double heading_error = std::abs(normalizeAngle(slam.currentPose().z() - robot.pose().z())) * 180.0 / M_PI;
    if (leg == 3) blind_heading = std::max(blind_heading, heading_error);
    const Eigen::Vector3d p = robot.pose();
    const double off = normalizeAngle(legs[leg].first - p.z());
    double v = 0.0, turn = 0.0;
    if (std::abs(off) > 0.01 && (turning || (p.head<2>() - leg_start.head<2>()).norm() < 0.01)) {
      turning = true;
      turn = std::clamp(2.0 * off, -0.6, 0.6);
    } else {
      turning = false;
      v = kSpeed;
      turn = 2.0 * off;
      if ((p.head<2>() - leg_start.head<2>()).norm() >= legs[leg].second) {
        ++leg;
        leg_start = p;
        v = 0.0;
      }
    }
    for (int k = 0; k < steps_per_scan; ++k) {
      robot.command(v, turn, t);
      robot.step(kSimStep, t, w);
      t += kSimStep;
    }
  }
  slam.flush();
  ASSERT_EQ(leg, legs.size()) << "the drive did not finish";
  const GraphSlamStats st = slam.stats();
  const double final_heading = std::abs(normalizeAngle(slam.currentPose().z() - robot.pose().z())) * 180.0 / M_PI;
  std::printf("back at a plain wall: %d partial closures of %d; heading error %.2f deg on the way back to the wall, "
              "%.3f deg at the end\n", st.closures_partial, st.closures_accepted, blind_heading, final_heading);
  EXPECT_GT(blind_heading, 2.0) << "blind, the heading should drift for this test to mean anything";
  EXPECT_GT(st.closures_partial, 0);
  // Without partial closures the heading stays where the blind loop left it (2.8 degrees); with
  // them it is brought back most of the way (to about 1 degree: the chain of the nodes tracked
  // since the wall came back into view holds the rest).
  EXPECT_LT(final_heading, 0.5 * blind_heading);
}

TEST(StraightRuns, RoomMatchesFixEveryDirection) {
  // The same drive inside a room 6 m x 4 m with a box and a pillar: walls every way, so each
  // match's weakest direction is pinned to about a centimetre.
  World2D w;
  w.addBox({1.0, 2.05}, 0, 6.2, 0.1);
  w.addBox({1.0, -2.05}, 0, 6.2, 0.1);
  w.addBox({-2.05, 0}, 0, 0.1, 4.2);
  w.addBox({4.05, 0}, 0, 0.1, 4.2);
  w.addBox({1.5, 1.5}, 0.4, 0.6, 0.4);
  w.addCylinder({2.5, -1.2}, 0.2);
  const RunResult r = driveStraight(w, {-1.0, 0.0, 0.0}, 0.0, 7, 2.4);
  std::printf("room: weakest direction's sigma %.4f m (median)\n", r.weakest_sigma_m);
  EXPECT_LT(r.weakest_sigma_m, 0.02);
}
