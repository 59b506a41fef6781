#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/motion_model.h"
#include "mbot_slam_navigation/core/pose2d.h"
#include "mbot_slam_navigation/core/rbpf_slam.h"
#include "mbot_slam_navigation/core/scan_matcher.h"
#include "mbot_slam_navigation/core/slam_grid.h"
#include "mbot_slam_navigation/core/world2d.h"

using namespace mbot::core;

namespace {
// An 8 m x 6 m room with a pillar and a cupboard, so that a scan fixes all three pose dimensions.
World2D syntheticRoom() {
  World2D w;
  w.addBox({0, 3.05}, 0, 8.2, 0.1);
  w.addBox({0, -3.05}, 0, 8.2, 0.1);
  w.addBox({4.05, 0}, 0, 0.1, 6.2);
  w.addBox({-4.05, 0}, 0, 0.1, 6.2);
  w.addBox({1.5, 1.0}, 0.4, 0.6, 0.6);
  w.addBox({-2.5, -2.2}, 0, 1.2, 0.8);
  w.addCylinder({-1.0, 1.5}, 0.3);
  return w;
}

LaserScan scanAt(const World2D& w, const Eigen::Vector3d& pose, std::mt19937& rng, double noise = 0.0) {
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = M_PI / 180;
  s.range_min_m = 0.1;
  s.range_max_m = 10.0;
  s.ranges_m.resize(360);
  w.castScan(pose, s.angle_min_rad, s.angle_increment_rad, 360, 0.1, 10.0, noise, 0.0, rng, s.ranges_m.data());
  return s;
}

ScanMatcherParams matcherParams() {
  ScanMatcherParams p;
  p.max_urange = 9.0;
  p.max_range = 10.0;
  return p;
}
}  // namespace

TEST(ScanMatcher, RecoversAKnownOffsetInASyntheticRoom) {
  const World2D room = syntheticRoom();
  std::mt19937 rng(11);
  const ScanMatcher matcher(matcherParams(), 0.05);
  SlamGrid map({-5, -4}, {5, 4}, 0.05);
  const Eigen::Vector3d truth(0.3, -0.4, 0.2);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, -1, 1.0), Eigen::Vector3d(-1, 0.5, -2.0)}) {
    matcher.registerScan(map, p, scanAt(room, p, rng));
  }
  const PreparedScan scan = matcher.prepare(scanAt(room, truth, rng, 0.01));
  for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0.15, -0.1, 0.05), Eigen::Vector3d(-0.1, 0.12, -0.06)}) {
    double score = 0;
    const Eigen::Vector3d start(truth.x() + offset.x(), truth.y() + offset.y(), truth.z() + offset.z());
    const Eigen::Vector3d found = matcher.optimize(map, start, scan, &score);
    EXPECT_NEAR(found.x(), truth.x(), 0.02);
    EXPECT_NEAR(found.y(), truth.y(), 0.02);
    EXPECT_NEAR(found.z(), truth.z(), 0.01);
    EXPECT_GT(score, matcher.score(map, start, scan));
  }
}

TEST(ScanMatcher, LikelihoodPrefersTheTruePose) {
  const World2D room = syntheticRoom();
  std::mt19937 rng(2);
  const ScanMatcher matcher(matcherParams(), 0.05);
  SlamGrid map({-5, -4}, {5, 4}, 0.05);
  matcher.registerScan(map, {0, 0, 0}, scanAt(room, {0, 0, 0}, rng));
  const PreparedScan scan = matcher.prepare(scanAt(room, {0.5, 0.2, 0.1}, rng));
  double s_true, l_true, s_off, l_off;
  matcher.likelihoodAndScore(map, {0.5, 0.2, 0.1}, scan, &s_true, &l_true);
  matcher.likelihoodAndScore(map, {0.6, 0.2, 0.1}, scan, &s_off, &l_off);
  EXPECT_GT(l_true, l_off);
  EXPECT_GT(s_true, s_off);
}

TEST(SlamGrid, GrowthKeepsOldCellsAndCopiesOnWrite) {
  SlamGrid a({0, 0}, {1, 1}, 0.05);
  a.registerBeam({0.1, 0.1}, {0.5, 0.5}, true);
  const Cell hit = a.worldToCell({0.5, 0.5});
  const Eigen::Vector2d hit_world = a.cellCenter(hit);
  ASSERT_EQ(a.cell(hit).hits, 1u);
  a.growToInclude({-3, -2}, {4, 1});
  const Cell moved = a.worldToCell(hit_world);
  EXPECT_EQ(a.cell(moved).hits, 1u);
  EXPECT_NEAR((a.hitMean(moved) - Eigen::Vector2d(0.5, 0.5)).norm(), 0.0, 1e-6);  // sub-cell hit point kept
  EXPECT_LE(a.origin().x(), -3.0);

  SlamGrid b = a;  // a particle copied at resampling: shares every patch
  EXPECT_EQ(b.ownedPatches(), 0);
  b.registerBeam({0.1, 0.1}, {0.5, 0.5}, true);
  EXPECT_EQ(b.cell(moved).hits, 2u);
  EXPECT_EQ(a.cell(moved).hits, 1u);  // the other copy did not change
  EXPECT_GT(b.ownedPatches(), 0);
  EXPECT_LT(b.ownedPatches(), b.allocatedPatches() + 1);
}

TEST(SlamGrid, OccupancyImageIsEveryCellsRatioCroppedToTheWrittenPatches) {
  SlamGrid g({0, 0}, {2, 2}, 0.05);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.5, 4.0);
  for (int k = 0; k < 300; ++k) g.registerBeam({u(rng), u(rng)}, {u(rng), u(rng)}, k % 3 != 0);  // grows the grid
  int occupied_before = std::numeric_limits<int>::max();
  for (double thresh : {0.0, 0.25, 0.5}) {
    const OccupancyImage img = g.toOccupancy(thresh);
    ASSERT_GT(img.width, 0);
    int known = 0, occupied = 0;
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) {
        const Eigen::Vector2d centre = img.origin + Eigen::Vector2d(x + 0.5, y + 0.5) * img.resolution;
        const HitCell& cell = g.cell(g.worldToCell(centre));
        const int expected = cell.visits == 0 ? -1 : (SlamGrid::occupied(cell, thresh) ? 100 : 0);
        ASSERT_EQ(img.data[static_cast<std::size_t>(y) * img.width + x], expected) << "cell " << x << ", " << y;
        known += expected >= 0;
        occupied += expected == 100;
      }
    }
    EXPECT_GT(known, 1000);
    EXPECT_GT(occupied, 0);
    EXPECT_LT(occupied, occupied_before);  // a higher threshold calls fewer cells occupied
    occupied_before = occupied;
  }
}

// A node publishing its map every few seconds redraws only the patches written since: the picture
// must be the whole conversion's, whether the new beams land inside the old picture, in patches
// outside it, or beyond the grid (which grows and shifts every patch's index).
TEST(SlamGrid, UpdatedOccupancyImageEqualsTheWholeConversionAfterEveryBatchOfBeams) {
  SlamGrid g({-10, -10}, {10, 10}, 0.05);
  g.trackWrites();
  std::mt19937 rng(12);
  OccupancyImage img;
  // Batches: small beams near the start (inside the picture), then farther (new patches), then
  // beyond the grid's first extent (growth), then near the start again.
  const double spread[] = {1.0, 1.0, 4.0, 1.0, 14.0, 2.0, 2.0};
  int redrawn_in_place = 0;
  for (double s : spread) {
    std::uniform_real_distribution<double> u(-s, s);
    for (int k = 0; k < 40; ++k) {
      const Eigen::Vector2d to(u(rng), u(rng));
      if (to.x() < -9.5 || to.y() < -9.5 || to.x() > 9.5 || to.y() > 9.5) g.growToInclude(to.array() - 1.0, to.array() + 1.0);
      g.registerBeam({0.02, 0.03}, to, k % 4 != 0);
    }
    const int8_t* buffer = img.data.data();  // a whole conversion puts a new vector in its place
    g.updateOccupancy(0.25, img);
    const OccupancyImage whole = g.toOccupancy(0.25);
    ASSERT_EQ(img.width, whole.width);
    ASSERT_EQ(img.height, whole.height);
    ASSERT_NEAR((img.origin - whole.origin).norm(), 0.0, 1e-9);
    ASSERT_TRUE(img.data == whole.data) << "after the batch spread " << s;
    redrawn_in_place += buffer != nullptr && img.data.data() == buffer;
  }
  EXPECT_GE(redrawn_in_place, 3);  // the batches near the start were drawn into the old picture
}

// Without trackWrites the grid knows nothing of what was written: every update is a whole one.
TEST(SlamGrid, UpdatedOccupancyImageOfAnUntrackedGridIsTheWholeConversion) {
  SlamGrid g({0, 0}, {4, 4}, 0.05);
  OccupancyImage img;
  g.registerBeam({1.0, 1.0}, {3.0, 2.0}, true);
  g.updateOccupancy(0.25, img);
  g.registerBeam({1.0, 1.0}, {1.0, 3.5}, true);
  g.updateOccupancy(0.25, img);
  EXPECT_TRUE(img.data == g.toOccupancy(0.25).data);
}

namespace {
int shown(const SlamGrid& g, const Eigen::Vector2d& p) {
  const OccupancyImage img = g.toOccupancy(0.25);
  const int x = static_cast<int>(std::floor((p.x() - img.origin.x()) / img.resolution));
  const int y = static_cast<int>(std::floor((p.y() - img.origin.y()) / img.resolution));
  return img.data[static_cast<std::size_t>(y) * img.width + x];
}
/// Occupied cells of the map within `r` of `p`.
int occupiedNear(const SlamGrid& g, const Eigen::Vector2d& p, double r) {
  int n = 0;
  for (double dx = -r; dx <= r + 1e-9; dx += g.resolution())
    for (double dy = -r; dy <= r + 1e-9; dy += g.resolution()) n += shown(g, p + Eigen::Vector2d(dx, dy)) == 100;
  return n;
}
}  // namespace

TEST(SlamGrid, APersonWhoLeftIsClearedWhileWallsSeenAtAGrazeStay) {
  // The robot at the origin turns in place in front of a door (a gap in the wall y = -1.3) in
  // which a person stands 0.25 m deep: 60 scans of 360 beams see them. They leave; the next
  // scans see through the door to the room's far wall 3 m beyond. gmapping's ratio alone keeps
  // the person's cells occupied until 180 scans have seen through them.
  World2D with_person;
  with_person.addBox({-1.5, -1.3}, 0, 2.0, 0.1);  // the wall, door x -0.5..0.5
  with_person.addBox({1.5, -1.3}, 0, 2.0, 0.1);
  with_person.addBox({0, -4.3}, 0, 6.0, 0.1);  // the far room's far wall
  World2D without = with_person;
  with_person.addCylinder({0.0, -1.55}, 0.25);
  SlamGrid g({-4, -5}, {4, 2}, 0.05);
  ScanMatcher m(matcherParams(), 0.05);
  std::mt19937 rng(3);
  for (int k = 0; k < 60; ++k) {
    const Eigen::Vector3d pose(0, 0, 0.1 * k);
    m.registerScan(g, pose, scanAt(with_person, pose, rng));
  }
  const Eigen::Vector2d person(0.0, -1.33);
  ASSERT_GE(occupiedNear(g, person, 0.1), 3) << "the person is not in the map";
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d pose(0, 0, 0.1 * k);
    m.registerScan(g, pose, scanAt(without, pose, rng));
  }
  EXPECT_EQ(occupiedNear(g, person, 0.15), 0) << "the person's cells show occupied after they left";
  EXPECT_GT(g.cell(g.worldToCell({0.0, -1.32})).occupancy(), 0.25);  // the ratio alone would keep it
  // The walls beside the door, seen at a graze from a robot driving along them 0.2 m away, stay:
  // the beams that pass through their cells end on them within kClearBeyond.
  int wall = 0, worn = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d pose(-3.5 + 0.035 * k, -1.05, 0.0);
    m.registerScan(g, pose, scanAt(without, pose, rng));
  }
  for (double x = -2.4; x < 2.4; x += 0.05) {
    if (std::abs(x) < 0.6) continue;  // the door
    ++wall;
    worn += shown(g, {x, -1.27}) != 100 && shown(g, {x, -1.32}) != 100;
  }
  EXPECT_GT(wall, 60);
  EXPECT_EQ(worn, 0) << "wall cells shown free after a drive along the wall";
}

TEST(MotionModel, SampleStatisticsMatchTheParameters) {
  MotionModelParams p;
  p.srr = 0.1;
  p.srt = 0.2;
  p.str = 0.1;
  p.stt = 0.2;
  const MotionModel model(p);
  std::mt19937 rng(5);
  const Eigen::Vector3d odom_old(1.0, 2.0, 0.5), odom_new = composePose(odom_old, {0.5, 0.0, 0.2});
  const Eigen::Vector3d expected_sd = model.stddev({0.5, 0.0, 0.2});
  EXPECT_NEAR(expected_sd.x(), 0.1 * 0.5 + 0.1 * 0.2, 1e-12);
  EXPECT_NEAR(expected_sd.z(), 0.2 * 0.2 + 0.2 * 0.5, 1e-12);
  const int n = 20000;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = relativePose(Eigen::Vector3d::Zero(), model.sample({0, 0, 0}, odom_new, odom_old, rng));
    // compare in the increment's own coordinates
    sum += d;
    sum2 += d.cwiseProduct(d);
  }
  const Eigen::Vector3d mean = sum / n;
  const Eigen::Vector3d sd = (sum2 / n - mean.cwiseProduct(mean)).cwiseSqrt();
  EXPECT_NEAR(mean.x(), 0.5, 0.005);
  EXPECT_NEAR(mean.z(), 0.2, 0.005);
  EXPECT_NEAR(sd.x(), expected_sd.x(), 0.004);
  EXPECT_NEAR(sd.y(), expected_sd.y(), 0.004);
  EXPECT_NEAR(sd.z(), expected_sd.z(), 0.004);
}

TEST(Resampling, KeepsTheBestParticleAndIsProportional) {
  const std::vector<double> w{0.01, 0.70, 0.04, 0.20, 0.05};
  for (double offset : {0.0, 0.05, 0.1, 0.1999}) {
    const auto idx = lowVarianceResample(w, offset);
    ASSERT_EQ(idx.size(), w.size());
    EXPECT_GE(std::count(idx.begin(), idx.end(), 1), 3);  // 0.7 * 5 = 3.5 copies: 3 or 4
    EXPECT_LE(std::count(idx.begin(), idx.end(), 1), 4);
    EXPECT_GE(std::count(idx.begin(), idx.end(), 3), 1);  // weight above 1/n: kept
    EXPECT_TRUE(std::is_sorted(idx.begin(), idx.end()));
  }
}

TEST(RbpfSlam, BeatsDriftingOdometryAroundTheRoom) {
  const World2D room = syntheticRoom();
  RbpfParams p;
  p.particles = 10;
  p.linear_update = 0.2;
  p.angular_update = 0.2;
  p.matcher = matcherParams();
  p.seed = 3;
  RbpfSlam slam(p);
  std::mt19937 rng(9);
  std::normal_distribution<double> slip(0.0, 0.03);
  Eigen::Vector3d truth(-2.5, 0.0, 0.0), odom = truth;
  // A lap around the room: 0.05 m steps, turning at the corners; odometry drifts (biased turn).
  double odom_err = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double ds = 0.05, dth = (i % 100 > 80) ? 0.075 : 0.0;
    truth = integrateArc(truth, ds, dth);
    odom = integrateArc(odom, ds * (1 + slip(rng)), dth * 1.05 + 0.002);
    slam.processScan(odom, scanAt(room, truth, rng, 0.01), i * 0.1);
  }
  odom_err = (odom.head<2>() - truth.head<2>()).norm();
  const Eigen::Vector3d est = slam.currentPose();
  EXPECT_GT(odom_err, 0.3);
  EXPECT_LT((est.head<2>() - truth.head<2>()).norm(), 0.1) << "odometry error was " << odom_err;
  EXPECT_LT(std::abs(normalizeAngle(est.z() - truth.z())), 0.05);
  EXPECT_GT(slam.updates(), 50);
}

// Laps of a 5 m x 3.5 m rectangle inside the synthetic room, clear of the furniture: each side a
// straight stretch, then a quarter turn over 1 m of arc; per 0.05 m step, the turn [rad].
std::vector<double> rectangleLaps(int laps) {
  std::vector<double> turns;
  for (int lap = 0; lap < laps; ++lap) {
    for (int straight : {74, 44, 74, 44}) {
      turns.insert(turns.end(), straight, 0.0);
      turns.insert(turns.end(), 20, M_PI / 40.0);
    }
  }
  return turns;
}

// Drives the laps with odometry that counts `distance_gain` of the distance and `turn_gain` of the
// turns; writes the mean and worst distance of currentPose() from the truth over every scan.
void driveLaps(const World2D& room, RbpfParams p, double distance_gain, double turn_gain, double* mean_err, double* max_err) {
  RbpfSlam slam(p);
  std::mt19937 rng(13);
  Eigen::Vector3d truth(-1.9, -1.2, 0.0), odom = truth;
  double sum = 0.0, worst = 0.0;
  const std::vector<double> turns = rectangleLaps(2);
  for (std::size_t i = 0; i < turns.size(); ++i) {
    truth = integrateArc(truth, 0.05, turns[i]);
    ASSERT_LT(std::abs(truth.x()), 3.4) << "the path leaves the room";
    ASSERT_LT(std::abs(truth.y() - 0.55), 2.4) << "the path leaves the room";
    odom = integrateArc(odom, 0.05 * distance_gain, turns[i] * turn_gain);
    if (slam.processScan(odom, scanAt(room, truth, rng, 0.01), i * 0.1)) {
      // The trajectory keeps the caller's odometry, whatever the filter moved with.
      EXPECT_LT((slam.trajectory().back().odom - odom).norm(), 1e-12);
    }
    const double err = (slam.currentPose().head<2>() - truth.head<2>()).norm();
    sum += err;
    worst = std::max(worst, err);
  }
  *mean_err = sum / turns.size();
  *max_err = worst;
}

// Wheels that count half the distance (slipping on a carpet) and turn 20% too far, with the
// filter's defaults otherwise (an update every metre or 0.5 rad of odometry): the particles spread
// from the prediction of whichever odometry the filter moves with, and the robot's pose follows
// that odometry between updates. On scan odometry the pose as published at every scan stays within
// centimetres; on the wheels' it falls a metre behind before an update, farther than the
// particles' matching reaches.
TEST(RbpfSlam, ScanOdometryHoldsThePoseWhereTheWheelsSlip) {
  const World2D room = syntheticRoom();
  RbpfParams p;
  p.particles = 10;
  p.matcher = matcherParams();
  p.seed = 4;
  p.tracking.matcher = p.matcher;
  double scan_mean, scan_max, wheel_mean, wheel_max, node_mean, node_max;
  driveLaps(room, p, 0.5, 1.2, &scan_mean, &scan_max);
  // As the node and slam_offline run it: the track's own noise (a tenth of gmapping's).
  RbpfParams q = p;
  q.motion = scanOdometryMotion();
  driveLaps(room, q, 0.5, 1.2, &node_mean, &node_max);
  p.scan_odometry = false;
  driveLaps(room, p, 0.5, 1.2, &wheel_mean, &wheel_max);
  EXPECT_LT(scan_mean, 0.04) << "wheels: " << wheel_mean;
  EXPECT_LT(scan_max, 0.15) << "wheels: " << wheel_max;
  EXPECT_LT(node_mean, 0.04) << "wheels: " << wheel_mean;
  EXPECT_LT(node_max, 0.15) << "wheels: " << wheel_max;
  EXPECT_GT(wheel_max, 0.3) << "scan odometry: " << scan_max;  // the case is one scan odometry is for
}

// Headings near +-pi: the improved proposal's samples around such a heading wrap, and their mean
// once came out 2 pi / (samples) off, which turned the particle round at an update (the pose then
// ran backwards). Exact odometry, both kinds of odometry: every scan within the filter's own noise.
TEST(RbpfSlam, HoldsThePoseWhenTheHeadingIsNearPi) {
  const World2D room = syntheticRoom();
  RbpfParams p;
  p.particles = 5;
  p.matcher = matcherParams();
  p.tracking.matcher = p.matcher;
  p.linear_update = 0.3;
  for (bool scan_odometry : {true, false}) {
    p.scan_odometry = scan_odometry;
    RbpfSlam slam(p);
    std::mt19937 rng(21);
    double worst = 0.0, worst_heading = 0.0;
    for (int i = 0; i < 100; ++i) {
      // Along y = 0.5 from x = 2.5 westwards, the heading +-pi (alternating sides of the wrap).
      const Eigen::Vector3d truth(2.5 - 0.05 * i, 0.5, (i % 2 ? 1.0 : -1.0) * (M_PI - 0.001));
      slam.processScan(truth, scanAt(room, truth, rng, 0.005), i * 0.1);
      const Eigen::Vector3d est = slam.currentPose();
      worst = std::max(worst, (est.head<2>() - truth.head<2>()).norm());
      worst_heading = std::max(worst_heading, std::abs(normalizeAngle(est.z() - truth.z())));
    }
    EXPECT_LT(worst, 0.15) << (scan_odometry ? "scan odometry" : "wheels");
    EXPECT_LT(worst_heading, 0.05) << (scan_odometry ? "scan odometry" : "wheels");
    EXPECT_GE(slam.updates(), 10);
  }
}

// The particles are matched on several threads (`threads`): each particle's update reads only its
// own map, so the filter must come out the same, particle by particle, whatever their number.
TEST(RbpfSlam, ThreadsDoNotChangeTheResult) {
  const World2D room = syntheticRoom();
  RbpfParams p;
  p.particles = 7;  // not a multiple of the thread counts: uneven shares
  p.matcher = matcherParams();
  p.tracking.matcher = p.matcher;
  p.linear_update = 0.2;
  p.seed = 8;
  std::vector<std::vector<Eigen::Vector3d>> poses;
  std::vector<std::vector<double>> weights;
  for (int threads : {1, 2, 3}) {
    p.threads = threads;
    RbpfSlam slam(p);
    std::mt19937 rng(17);
    Eigen::Vector3d truth(-2.5, 0.0, 0.0);
    for (int i = 0; i < 120; ++i) {
      truth = integrateArc(truth, 0.05, (i % 40 > 30) ? 0.1 : 0.0);
      slam.processScan(truth, scanAt(room, truth, rng, 0.01), i * 0.1);
    }
    ASSERT_GT(slam.updates(), 20);
    poses.emplace_back();
    weights.emplace_back();
    for (const Particle& q : slam.particles()) {
      poses.back().push_back(q.pose);
      weights.back().push_back(q.weight_sum);
    }
  }
  for (std::size_t t = 1; t < poses.size(); ++t) {
    for (std::size_t i = 0; i < poses[0].size(); ++i) {
      EXPECT_EQ(poses[t][i], poses[0][i]) << "particle " << i << ", " << t + 1 << " threads";
      EXPECT_EQ(weights[t][i], weights[0][i]) << "particle " << i << ", " << t + 1 << " threads";
    }
  }
}

// best_switch_margin: the particle published at an update descends from the one published at the
// last update whenever a descendant survives and the best particle does not beat it by more than
// the margin; 0 publishes the highest accumulated weight, as gmapping. On the wheels' odometry
// (slipping, gmapping's noise) the best particle changes often; the margin keeps the lineage.
TEST(RbpfSlam, ThePublishedParticleKeepsItsLineageWithinTheMargin) {
  const World2D room = syntheticRoom();
  const std::vector<double> turns = rectangleLaps(1);
  int switches[2] = {0, 0};
  for (int m = 0; m < 2; ++m) {
    RbpfParams p;
    p.particles = 10;
    p.matcher = matcherParams();
    p.scan_odometry = false;
    p.linear_update = 0.3;
    p.seed = 5;
    p.best_switch_margin = m == 0 ? 0.0 : 4.0;
    RbpfSlam slam(p);
    std::mt19937 rng(17);
    Eigen::Vector3d truth(-1.9, -1.2, 0.0), odom = truth;
    std::shared_ptr<const TrajectoryNode> published;
    const double scale = p.ogain * p.particles;
    for (std::size_t i = 0; i < turns.size(); ++i) {
      truth = integrateArc(truth, 0.05, turns[i]);
      odom = integrateArc(odom, 0.05 * 0.8, turns[i] * 1.1);
      if (!slam.processScan(odom, scanAt(room, truth, rng, 0.01), i * 0.1)) continue;
      const auto& ps = slam.particles();
      int top = 0, lineage = -1;
      for (int k = 0; k < static_cast<int>(ps.size()); ++k) {
        if (ps[k].weight_sum > ps[top].weight_sum) top = k;
        if (published && ps[k].node->parent == published && (lineage < 0 || ps[k].weight_sum > ps[lineage].weight_sum)) lineage = k;
      }
      const Particle& chosen = slam.best();
      if (lineage >= 0 && (ps[top].weight_sum - ps[lineage].weight_sum) / scale <= p.best_switch_margin) {
        EXPECT_EQ(chosen.node->parent, published) << "left its lineage at scan " << i;
        EXPECT_EQ(chosen.weight_sum, ps[lineage].weight_sum);
      } else {
        EXPECT_EQ(chosen.weight_sum, ps[top].weight_sum) << "did not take the best particle at scan " << i;
      }
      if (published && chosen.node->parent != published) ++switches[m];
      published = chosen.node;
    }
    EXPECT_GT(slam.updates(), 20);
  }
  EXPECT_GT(switches[0], 3) << "the case needs changes of best particle";
  EXPECT_LT(switches[1], switches[0]);
}

TEST(RbpfSlam, RejectsBadParametersByName) {
  RbpfParams p;
  p.particles = 0;
  EXPECT_THROW(RbpfSlam{p}, std::invalid_argument);
  // Each bad value alone, over the defaults: the message names the parameter.
  auto expectNamed = [](void (*spoil)(RbpfParams&), const std::string& name) {
    RbpfParams q;
    spoil(q);
    try {
      RbpfSlam s(q);
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  expectNamed([](RbpfParams& q) { q.threads = 0; }, "threads");
  expectNamed([](RbpfParams& q) { q.best_switch_margin = -1; }, "best_switch_margin");
  expectNamed([](RbpfParams& q) { q.motion.srr = -1; }, "srr");
}
