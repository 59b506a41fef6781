#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/grid_raycast.h"
#include "mbot_slam_navigation/core/occupancy_grid.h"

using mbot::core::castRay;
using mbot::core::Cell;
using mbot::core::LaserScan;
using mbot::core::LogOddsModel;
using mbot::core::OccupancyGrid;

TEST(OccupancyGrid, RejectsBadGeometryWithAMessage) {
  EXPECT_THROW(OccupancyGrid(0, 10, 0.05, {0, 0}), std::invalid_argument);
  try {
    OccupancyGrid(10, 10, -0.05, {0, 0});
    FAIL() << "negative resolution accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LogOddsModel::fromProbabilities(0.4, 0.3), std::invalid_argument);
}

TEST(OccupancyGrid, WorldCellRoundTrip) {
  const OccupancyGrid grid(200, 100, 0.05, {-3.0, -1.5});
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(-3.0, 7.0), uy(-1.5, 3.5);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    const Cell c = grid.worldToCell(p);
    ASSERT_TRUE(grid.contains(c));
    const Eigen::Vector2d centre = grid.cellCenter(c);
    EXPECT_LE(std::abs(centre.x() - p.x()), 0.025 + 1e-9);
    EXPECT_LE(std::abs(centre.y() - p.y()), 0.025 + 1e-9);
    EXPECT_EQ(grid.worldToCell(centre), c);
  }
  EXPECT_EQ(grid.worldToCell({-3.0, -1.5}), (Cell{0, 0}));
  EXPECT_EQ(grid.worldToCell({-3.001, -1.5}), (Cell{-1, 0}));  // floor, not truncation toward zero
}

TEST(OccupancyGrid, OutOfBoundsAccessThrowsAndBeamsAreClipped) {
  OccupancyGrid grid(10, 10, 0.1, {0, 0});
  EXPECT_FALSE(grid.contains({10, 0}));
  EXPECT_FALSE(grid.contains({-1, 5}));
  EXPECT_THROW(grid.logOdds({10, 0}), std::out_of_range);
  EXPECT_THROW(grid.setLogOdds({0, -1}, 1.0f), std::out_of_range);
  // A beam starting outside and ending outside still updates the cells it crosses inside.
  grid.integrateBeam({-0.55, 0.55}, {1.55, 0.55}, true);
  for (int x = 0; x < 10; ++x) EXPECT_LT(grid.logOdds({x, 5}), 0.0f) << x;
  EXPECT_FALSE(grid.observed({5, 6}));
}

TEST(OccupancyGrid, BeamFreesTheRayAndMarksTheEndCell) {
  OccupancyGrid grid(40, 40, 0.05, {0, 0});
  const LogOddsModel m = grid.model();
  grid.integrateBeam({0.025, 0.025}, {1.025, 0.525}, true);
  const Cell end = grid.worldToCell({1.025, 0.525});
  EXPECT_FLOAT_EQ(grid.logOdds(end), m.hit);
  EXPECT_FLOAT_EQ(grid.logOdds({0, 0}), m.miss);
  EXPECT_GT(grid.probability(end), 0.5);
  // Repeated hits saturate at the clamp, so free space can still be re-learnt later.
  for (int i = 0; i < 100; ++i) grid.integrateBeam({0.025, 0.025}, {1.025, 0.525}, true);
  EXPECT_FLOAT_EQ(grid.logOdds(end), m.max);
  EXPECT_FLOAT_EQ(grid.logOdds({0, 0}), m.min);
}

TEST(OccupancyGrid, ScanFollowsRep117) {
  OccupancyGrid grid(100, 100, 0.05, {-2.5, -2.5});
  LaserScan scan;
  scan.angle_min_rad = 0.0;
  scan.angle_increment_rad = M_PI / 2;
  scan.range_min_m = 0.1;
  scan.range_max_m = 2.0;
  const float inf = std::numeric_limits<float>::infinity();
  scan.ranges_m = {1.0f, inf, std::nanf(""), -inf};  // east hit, north no return, west invalid, south too close
  EXPECT_EQ(grid.integrateScan({0.0, 0.0, 0.0}, scan, 1.5), 2);
  EXPECT_GT(grid.probability(grid.worldToCell({1.01, 0.0})), 0.5);
  EXPECT_LT(grid.probability(grid.worldToCell({0.0, 1.4})), 0.5);    // cleared up to the usable range
  EXPECT_FALSE(grid.observed(grid.worldToCell({0.0, 1.6})));          // but not beyond it
  EXPECT_FALSE(grid.observed(grid.worldToCell({-0.5, 0.0})));         // NaN beam skipped
  EXPECT_FALSE(grid.observed(grid.worldToCell({0.0, -0.5})));         // -inf beam skipped
  const auto data = grid.toRosData();
  const Cell hit = grid.worldToCell({1.01, 0.0});
  EXPECT_EQ(data[hit.y * 100 + hit.x], 70);  // one hit at p = 0.7
  EXPECT_EQ(data[0], -1);
}

TEST(OccupancyGrid, GrowingKeepsOldCellsInPlace) {
  OccupancyGrid grid(20, 20, 0.1, {0, 0});
  grid.setLogOdds({3, 4}, 2.0f);
  const Eigen::Vector2d marked = grid.cellCenter({3, 4});
  grid.growToInclude({-1.0, 3.0}, 0.5);
  EXPECT_GE(grid.width(), 35);
  EXPECT_GE(grid.height(), 35);
  const Cell moved = grid.worldToCell(marked);
  EXPECT_FLOAT_EQ(grid.logOdds(moved), 2.0f);
  EXPECT_EQ(grid.observedCount(), 1);
  EXPECT_TRUE(grid.contains(grid.worldToCell({-1.5, 3.5})));
  const int w = grid.width();
  grid.growToInclude({0.5, 0.5}, 0.1);  // already inside: unchanged
  EXPECT_EQ(grid.width(), w);
}

TEST(GridRaycast, DistanceToAWallIsExactToTheCellBoundary) {
  OccupancyGrid grid(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) grid.setLogOdds({80, y}, 5.0f);  // wall face at x = 4.0 m
  EXPECT_NEAR(castRay(grid, {1.0, 2.5}, 0.0, 10.0), 3.0, 1e-9);
  EXPECT_NEAR(castRay(grid, {1.0, 1.0}, M_PI / 4, 10.0), 3.0 * std::sqrt(2.0), 0.08);
  EXPECT_TRUE(std::isinf(castRay(grid, {1.0, 2.5}, M_PI, 10.0)));  // leaves the grid, no hit
  EXPECT_TRUE(std::isinf(castRay(grid, {1.0, 2.5}, 0.0, 2.0)));     // wall beyond max range
  EXPECT_EQ(castRay(grid, grid.cellCenter({80, 10}), 1.0, 10.0), 0.0);
}
