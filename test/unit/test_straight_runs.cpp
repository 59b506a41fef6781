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

/// Drives `run_m` metres along +x from `start` (world frame) at kSpeed, scanning at 10 Hz.
RunResult driveStraight(const World2D& world, const Eigen::Vector3d& start, double slip, unsigned seed,
                        double run_m = kRun) {
  DiffDriveParams drive_params;
  drive_params.wheel_separation_m = 0.38;
  drive_params.wheel_diameter_m = 0.12;
  drive_params.wheel_acceleration_mps2 = 1.0;
  drive_params.slip_stddev = slip;
  drive_params.odometry_from_world = slip <= 0.0;
  const Polygon footprint = {{0.2, 0.2}, {-0.2, 0.2}, {-0.2, -0.2}, {0.2, -0.2}};
  DiffDrive robot(drive_params, footprint, start, seed);
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
