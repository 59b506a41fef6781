// amcl's core: map, motion models, laser models, KLD resampling, recovery, estimates.
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/amcl.h"
#include "mbot_slam_navigation/core/pose2d.h"

using mbot::core::Amcl;
using mbot::core::AmclMap;
using mbot::core::AmclParams;
using mbot::core::LaserModel;
using mbot::core::LaserScan;
using mbot::core::OdomModel;

namespace {

// A 10 m x 8 m room at 0.05 m with an L-shaped inner wall and a box: no symmetry to confuse a
// global localization. Origin at (-1, -1).
std::shared_ptr<AmclMap> roomMap() {
  const int w = 200, h = 160;
  std::vector<int8_t> data(w * h, 0);
  auto occ = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) data[y * w + x] = 100;
  };
  occ(0, 0, w - 1, 1);
  occ(0, h - 2, w - 1, h - 1);
  occ(0, 0, 1, h - 1);
  occ(w - 2, 0, w - 1, h - 1);
  occ(60, 40, 61, 120);   // inner wall
  occ(60, 119, 110, 120);  // its foot
  occ(140, 30, 160, 50);  // box
  return std::make_shared<AmclMap>(w, h, 0.05, Eigen::Vector2d(-1.0, -1.0), data);
}

// A scan as a laser at `pose` (base = laser) sees the map: 360 beams over 2 pi, range_max 8 m.
LaserScan scanAt(const AmclMap& map, const Eigen::Vector3d& pose, double noise = 0.0, unsigned seed = 1) {
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = 2 * M_PI / 360;
  s.range_min_m = 0.1;
  s.range_max_m = 8.0;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  for (int i = 0; i < 360; ++i) {
    const double r = map.castRange(pose.x(), pose.y(), pose.z() + s.beamAngle(i), s.range_max_m);
    s.ranges_m.push_back(r >= s.range_max_m ? INFINITY : static_cast<float>(r + (noise > 0 ? n(rng) : 0.0)));
  }
  return s;
}

double distance2d(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).head<2>().norm(); }

}  // namespace

TEST(AmclMap, StatesDistancesAndRanges) {
  const auto map = roomMap();
  EXPECT_EQ(map->state(0, 0), 1);
  EXPECT_EQ(map->state(10, 10), -1);
  EXPECT_EQ(map->state(-1, 10), 0);
  const auto& d = map->occupiedDistance(2.0);
  // Cell (10, 10): nearest wall cell centre is x = 1 -> 9 cells = 0.45 m.
  EXPECT_NEAR(d[10 * 200 + 10], 0.45, 1e-5);
  EXPECT_FLOAT_EQ(d[80 * 200 + 30], 29 * 0.05f);  // to the wall at x = 1
  // From (0, 2) facing +x the inner wall starts at cell 60: x = -1 + 3.0 = 2.0.
  EXPECT_NEAR(map->castRange(0.0, 2.0, 0.0, 8.0), 2.0, 0.06);
  EXPECT_NEAR(map->castRange(0.0, 2.0, 0.0, 1.0), 1.0, 1e-9);
  EXPECT_THROW(AmclMap(10, 10, 0.05, Eigen::Vector2d::Zero(), std::vector<int8_t>(99)), std::invalid_argument);
}

TEST(Amcl, ParametersAreValidatedWithTheirRosNames) {
  AmclParams p;
  p.max_particles = 10;
  p.min_particles = 50;
  try {
    Amcl a(p, 1);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_particles"), std::string::npos);
  }
  p = AmclParams();
  p.alpha3 = -1;
  EXPECT_THROW(Amcl(p, 1), std::invalid_argument);
  p = AmclParams();
  p.max_beams = 1;
  EXPECT_THROW(Amcl(p, 1), std::invalid_argument);
}

TEST(Amcl, KldLimitMatchesRosFormula) {
  AmclParams p;
  p.min_particles = 1;
  p.max_particles = 100000;
  p.kld_err = 0.05;
  p.kld_z = 0.99;
  Amcl a(p, 1);
  EXPECT_EQ(a.resampleLimit(1), 100000);
  // k = 2: b = 2/9, x = 1 - b + sqrt(b) * 0.99 = 1.24449; n = ceil(1 / 0.1 * x^3) = 20
  EXPECT_EQ(a.resampleLimit(2), 20);
  // k = 100: ceil(99 / 0.1 * (1 - 2/891 + sqrt(2/891) * 0.99)^3) = 1129
  EXPECT_EQ(a.resampleLimit(100), 1129);
}

TEST(Amcl, DiffModelWithoutNoiseMovesParticlesInTheirOwnFrame) {
  AmclParams p;
  p.alpha1 = p.alpha2 = p.alpha3 = p.alpha4 = 0.0;
  p.min_particles = p.max_particles = 10;
  Amcl a(p, 1);
  a.initGaussian(Eigen::Vector3d(1.0, 1.0, M_PI / 2), Eigen::Matrix3d::Zero());
  // Odometry: 1 m forward then a 90 degree turn left, seen from odom yaw 0.
  a.motionUpdate(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1.0, 0.0, M_PI / 2));
  for (const auto& q : a.particles()) {
    EXPECT_NEAR(q.pose.x(), 1.0, 1e-9);
    EXPECT_NEAR(q.pose.y(), 2.0, 1e-9);
    EXPECT_NEAR(q.pose.z(), -M_PI, 1e-9 + 2 * M_PI * (q.pose.z() > 0));  // +-pi
  }
  // Backwards: 0.5 m reversing is a translation of 0.5 m without turning round.
  a.motionUpdate(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-0.5, 0.0, 0.0));
  for (const auto& q : a.particles()) {
    EXPECT_NEAR(q.pose.x(), 1.5, 1e-9);
    EXPECT_NEAR(q.pose.y(), 2.0, 1e-9);
  }
}

TEST(Amcl, DiffModelNoiseIsAStandardDeviationNotAVariance) {
  // alpha3 = 0.04 on a 1 m straight move: sd(translation) = sqrt(0.04) * 1 m = 0.2 m. ROS's "diff"
  // would use 0.04 * 1^2 = 0.04 m as the standard deviation.
  AmclParams p;
  p.alpha1 = p.alpha2 = p.alpha4 = 0.0;
  p.alpha3 = 0.04;
  p.min_particles = p.max_particles = 20000;
  Amcl a(p, 7);
  a.initGaussian(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
  a.motionUpdate(Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 0.0));
  double m = 0, m2 = 0;
  for (const auto& q : a.particles()) {
    m += q.pose.x();
    m2 += q.pose.x() * q.pose.x();
  }
  m /= a.particles().size();
  const double sd = std::sqrt(m2 / a.particles().size() - m * m);
  EXPECT_NEAR(m, 1.0, 0.01);
  EXPECT_NEAR(sd, 0.2, 0.01);
}

TEST(Amcl, OmniModelFollowsSidewaysMotion) {
  AmclParams p;
  p.odom_model = OdomModel::kOmni;
  p.alpha1 = p.alpha2 = p.alpha3 = p.alpha4 = p.alpha5 = 0.0;
  p.min_particles = p.max_particles = 5;
  Amcl a(p, 1);
  a.initGaussian(Eigen::Vector3d(0, 0, M_PI), Eigen::Matrix3d::Zero());
  // Odometry says: 1 m to the robot's left (odom yaw 0 -> +y), no turn.
  a.motionUpdate(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 1.0, 0.0));
  for (const auto& q : a.particles()) {
    EXPECT_NEAR(q.pose.x(), 0.0, 1e-9);
    EXPECT_NEAR(q.pose.y(), -1.0, 1e-9);  // the particle faces -x: its left is -y
  }
}

TEST(Amcl, LaserModelsPreferTheTruePose) {
  const auto map = roomMap();
  const Eigen::Vector3d truth(1.0, 2.5, 0.3);
  const LaserScan scan = scanAt(*map, truth, 0.02);
  for (LaserModel model : {LaserModel::kLikelihoodField, LaserModel::kBeam}) {
    AmclParams p;
    p.laser_model = model;
    p.min_particles = p.max_particles = 1;
    double w_true = 0, w_off = 0;
    for (int k = 0; k < 2; ++k) {
      Amcl a(p, 1);
      a.setMap(map);
      const Eigen::Vector3d pose = k == 0 ? truth : Eigen::Vector3d(truth + Eigen::Vector3d(0.3, 0, 0.1));
      a.initGaussian(pose, Eigen::Matrix3d::Zero());
      a.sensorUpdate(scan, Eigen::Vector3d::Zero());
      (k == 0 ? w_true : w_off) = a.wFast();  // the mean weight of one particle: its likelihood
    }
    EXPECT_GT(w_true, 1.5 * w_off) << "model " << static_cast<int>(model);
  }
}

TEST(Amcl, AWideSearchPutsItsParticlesOnlyInFreeCells) {
  // The recovery's search after a carry: a 1.5 m normal around the last estimate. Drawn as it is,
  // a share of the particles lands in walls and outside the room, where the robot cannot be;
  // free_only draws them again.
  const auto map = roomMap();
  AmclParams p;
  p.max_particles = 3000;
  Amcl a(p, 7);
  a.setMap(map);
  const Eigen::Vector3d near_wall(0.2, 0.2, 0.0);  // 1.2 m from the room's corner
  const Eigen::Matrix3d cov = Eigen::Vector3d(2.25, 2.25, M_PI * M_PI).asDiagonal();
  auto outside = [&]() {
    int n = 0;
    for (const auto& q : a.particles()) {
      const int cx = static_cast<int>(std::floor((q.pose.x() + 1.0) / 0.05));
      const int cy = static_cast<int>(std::floor((q.pose.y() + 1.0) / 0.05));
      n += map->state(cx, cy) != -1;
    }
    return n;
  };
  a.initGaussian(near_wall, cov);
  EXPECT_GT(outside(), 300);  // as drawn: many in walls or off the map
  a.initGaussian(near_wall, cov, true);
  EXPECT_EQ(outside(), 0);
  EXPECT_EQ(a.particles().size(), 3000u);
}

TEST(Amcl, TrackingConvergesOnTheTruePoseFromAnOffsetGuess) {
  const auto map = roomMap();
  AmclParams p;
  p.min_particles = 500;
  p.max_particles = 5000;
  p.kld_err = 0.05;
  Amcl a(p, 3);
  a.setMap(map);
  Eigen::Vector3d truth(0.5, 4.0, 0.0), odom(0, 0, 0);
  a.initGaussian(Eigen::Vector3d(1.0, 3.6, 0.15), Eigen::Vector3d(0.25, 0.25, 0.07).asDiagonal());
  std::mt19937 rng(5);
  std::normal_distribution<double> slip(0.0, 0.01);
  for (int i = 0; i < 15; ++i) {
    // Drive 0.2 m along x per step; odometry slips a little.
    const Eigen::Vector3d step(0.2, 0.0, 0.0);
    const Eigen::Vector3d new_odom = mbot::core::composePose(odom, step + Eigen::Vector3d(slip(rng), slip(rng), 0));
    truth = mbot::core::composePose(truth, step);
    a.motionUpdate(odom, new_odom);
    odom = new_odom;
    a.sensorUpdate(scanAt(*map, truth, 0.02, i), Eigen::Vector3d::Zero());
    a.resample();
  }
  const auto e = a.estimate();
  EXPECT_LT(distance2d(e.mean, truth), 0.08) << e.mean.transpose() << " vs " << truth.transpose();
  EXPECT_LT(std::fabs(mbot::core::normalizeAngle(e.mean.z() - truth.z())), 0.05);
  EXPECT_GT(e.cluster_weight, 0.9);
  // KLD: a converged filter needs far fewer than max_particles.
  EXPECT_LT(static_cast<int>(a.particles().size()), 2000);
  EXPECT_GE(static_cast<int>(a.particles().size()), p.min_particles);
}

TEST(Amcl, GlobalLocalizationFindsTheRobotWhileItDrives) {
  const auto map = roomMap();
  AmclParams p;
  p.min_particles = 500;
  p.max_particles = 20000;
  p.kld_err = 0.05;
  p.alpha1 = p.alpha2 = p.alpha3 = p.alpha4 = 0.05;
  Amcl a(p, 11);
  a.setMap(map);
  a.initUniform();
  EXPECT_EQ(static_cast<int>(a.particles().size()), 20000);
  Eigen::Vector3d truth(7.0, 1.0, M_PI / 2), odom(0, 0, 0);
  for (int i = 0; i < 25; ++i) {
    const Eigen::Vector3d step = (i % 8 < 6) ? Eigen::Vector3d(0.2, 0, 0) : Eigen::Vector3d(0, 0, 0.5);
    truth = mbot::core::composePose(truth, step);
    const Eigen::Vector3d new_odom = mbot::core::composePose(odom, step);
    a.motionUpdate(odom, new_odom);
    odom = new_odom;
    a.sensorUpdate(scanAt(*map, truth, 0.02, 100 + i), Eigen::Vector3d::Zero());
    a.resample();
  }
  const auto e = a.estimate();
  EXPECT_LT(distance2d(e.mean, truth), 0.15) << e.mean.transpose() << " vs " << truth.transpose();
}

TEST(Amcl, SystematicResamplingKeepsProportionsAndConcentratesOnHeavyParticles) {
  const auto map = roomMap();
  AmclParams p;
  p.min_particles = 1000;
  p.max_particles = 1000;
  Amcl a(p, 2);
  a.setMap(map);
  a.initUniform();
  // A scan from one pose makes a few particles heavy; after resampling, copies of heavy particles
  // dominate, and the count stays within [min, max].
  a.sensorUpdate(scanAt(*map, Eigen::Vector3d(2.0, 2.0, 0.0)), Eigen::Vector3d::Zero());
  double w_max = 0;
  for (const auto& q : a.particles()) w_max = std::max(w_max, q.weight);
  const Eigen::Vector3d heavy = std::max_element(a.particles().begin(), a.particles().end(), [](auto& x, auto& y) {
                                  return x.weight < y.weight;
                                })->pose;
  a.resample();
  EXPECT_EQ(static_cast<int>(a.particles().size()), 1000);
  int copies = 0;
  for (const auto& q : a.particles()) copies += (q.pose - heavy).norm() < 1e-12;
  // Systematic resampling gives floor or ceil of n * w copies.
  EXPECT_GE(copies, static_cast<int>(std::floor(1000 * w_max)));
  EXPECT_LE(copies, static_cast<int>(std::ceil(1000 * w_max)));
}

TEST(Amcl, RecoveryInjectsRandomParticlesWhenTheLikelihoodDrops) {
  const auto map = roomMap();
  AmclParams p;
  p.min_particles = p.max_particles = 2000;
  p.recovery_alpha_slow = 0.001;
  p.recovery_alpha_fast = 0.1;
  Amcl a(p, 4);
  a.setMap(map);
  const Eigen::Vector3d where(1.0, 2.0, 0.0);
  a.initGaussian(where, Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal());
  for (int i = 0; i < 5; ++i) {
    a.sensorUpdate(scanAt(*map, where), Eigen::Vector3d::Zero());
    a.resample();
  }
  auto far = [&] {
    int n = 0;
    for (const auto& q : a.particles()) n += distance2d(q.pose, where) > 1.0;
    return n;
  };
  EXPECT_EQ(far(), 0);
  // Kidnapped: the scans now come from elsewhere; w_fast falls below w_slow.
  for (int i = 0; i < 5; ++i) a.sensorUpdate(scanAt(*map, Eigen::Vector3d(7.0, 5.0, 2.0)), Eigen::Vector3d::Zero());
  EXPECT_LT(a.wFast(), a.wSlow());
  a.resample();
  EXPECT_GT(far(), 100);
}
