#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/inflation_layer.h"

using namespace mbot::core;

TEST(Costmap, OccupancyGridValuesAsCostmap2dPublishesThem) {
  Costmap m(6, 1, 0.05, {0, 0});
  const uint8_t in[6] = {0, 1, 128, 252, 253, 254};
  for (int x = 0; x < 6; ++x) m.setCost({x, 0}, in[x]);
  const auto out = m.toOccupancyData();
  EXPECT_EQ(out[0], 0);
  EXPECT_EQ(out[1], 1);
  EXPECT_GT(out[2], 1);
  EXPECT_LT(out[2], 98);
  EXPECT_EQ(out[3], 98);
  EXPECT_EQ(out[4], 99);
  EXPECT_EQ(out[5], 100);
  m.setCost({0, 0}, cost::kNoInformation);
  EXPECT_EQ(m.toOccupancyData()[0], -1);
  EXPECT_EQ(costFromOccupancy(100), cost::kLethal);
  EXPECT_EQ(costFromOccupancy(-1), cost::kNoInformation);
  EXPECT_EQ(costFromOccupancy(-1, 100, false), cost::kFree);
  EXPECT_EQ(costFromOccupancy(65), cost::kFree);
}

TEST(Costmap, RollingWindowKeepsOverlappingCells) {
  Costmap m(10, 10, 0.1, {0, 0});
  m.setCost({5, 5}, 200);
  m.moveOrigin({0.3, -0.2});
  EXPECT_NEAR(m.origin().x(), 0.3, 1e-9);
  EXPECT_EQ(m.cost({2, 7}), 200);  // the same world cell, new index
  EXPECT_EQ(m.cost({9, 0}), cost::kNoInformation);
}

TEST(Inflation, ValuesFollowTheCostmap2dFormula) {
  InflationParams p;
  p.inscribed_radius = 0.2;
  p.inflation_radius = 0.6;
  p.cost_scaling_factor = 10.0;
  Costmap m(101, 101, 0.05, {0, 0});
  m.setCost({50, 50}, cost::kLethal);
  inflate(m, p);
  EXPECT_EQ(m.cost({50, 50}), cost::kLethal);
  EXPECT_EQ(m.cost({54, 50}), cost::kInscribed);  // 0.20 m: inscribed
  for (int k = 5; k <= 12; ++k) {                 // 0.25 .. 0.60 m along x
    const double d = k * 0.05;
    EXPECT_EQ(m.cost({50 + k, 50}), static_cast<uint8_t>(252 * std::exp(-10.0 * (d - 0.2)))) << d;
  }
  EXPECT_EQ(m.cost({50 + 13, 50}), 0);  // beyond the inflation radius
  // Diagonal: exact Euclidean distance (0.35 m * sqrt 2 = 0.495 m)
  EXPECT_EQ(m.cost({57, 57}), static_cast<uint8_t>(252 * std::exp(-10.0 * (0.35 * std::sqrt(2.0) - 0.2))));
}

TEST(Inflation, UnknownCellsOnlyTakeInscribedCostsByDefault) {
  InflationParams p;
  Costmap m(40, 1, 0.05, {0, 0}, cost::kNoInformation);
  m.setCost({0, 0}, cost::kLethal);
  inflate(m, p);
  EXPECT_EQ(m.cost({2, 0}), cost::kInscribed);        // 0.10 m <= inscribed 0.2
  EXPECT_EQ(m.cost({6, 0}), cost::kNoInformation);    // 0.30 m: inflated cost < 253 keeps unknown
  p.inflate_unknown = true;
  inflate(m, p);
  EXPECT_LT(m.cost({6, 0}), cost::kInscribed);
}

namespace {
// Brute force: every cell's cost from its exact distance to every lethal cell.
Costmap bruteInflation(const Costmap& m, const InflationParams& p) {
  Costmap out = m;
  for (int y = 0; y < m.height(); ++y) {
    for (int x = 0; x < m.width(); ++x) {
      double best = std::numeric_limits<double>::infinity();
      for (int v = 0; v < m.height(); ++v) {
        for (int u = 0; u < m.width(); ++u) {
          if (m.cost({u, v}) == cost::kLethal) best = std::min(best, std::hypot(u - x, v - y) * m.resolution());
        }
      }
      if (!std::isfinite(best)) continue;
      const uint8_t c = inflatedCost(best, p), old = m.cost({x, y});
      if (old == cost::kNoInformation) {
        if (p.inflate_unknown ? c > 0 : c >= cost::kInscribed) out.setCost({x, y}, c);
      } else if (c > old) {
        out.setCost({x, y}, c);
      }
    }
  }
  return out;
}

Costmap randomCostmap(int w, int h, unsigned seed, int lethal_per_mille) {
  std::srand(seed);
  Costmap m(w, h, 0.05, {0, 0});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int r = std::rand() % 1000;
      m.setCost({x, y}, r < lethal_per_mille ? cost::kLethal : r < 2 * lethal_per_mille ? cost::kNoInformation
                                                                  : static_cast<uint8_t>(std::rand() % 60));
    }
  }
  return m;
}
}  // namespace

TEST(Inflation, MatchesBruteForceOnRandomGrids) {
  InflationParams p;
  p.inscribed_radius = 0.12;
  p.inflation_radius = 0.4;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    p.inflate_unknown = seed % 2 == 0;
    const Costmap m = randomCostmap(37, 29, seed, seed * 4);  // sparse to dense obstacles
    Costmap fast = m;
    inflate(fast, p);
    EXPECT_EQ(fast.costs(), bruteInflation(m, p).costs()) << "seed " << seed;
  }
}

TEST(Inflation, AWindowIsInflatedAsTheWholeMapAndNothingOutsideItChanges) {
  InflationParams p;
  p.inflation_radius = 0.3;
  const Costmap base = randomCostmap(60, 50, 9, 8);
  Costmap whole = base;
  inflate(whole, p);
  Costmap out(60, 50, 0.05, {0, 0}, 77);  // 77: a value neither layer produces here
  const CellWindow win{10, 5, 31, 40};
  inflateWindow(base, out, win, p);
  for (int y = 0; y < 50; ++y) {
    for (int x = 0; x < 60; ++x) {
      const bool inside = x >= win.x0 && x < win.x1 && y >= win.y0 && y < win.y1;
      ASSERT_EQ(out.cost({x, y}), inside ? whole.cost({x, y}) : 77) << x << ", " << y;
    }
  }
  EXPECT_TRUE((CellWindow{0, 0, 0, 5}).empty());
  const CellWindow u = CellWindow{2, 3, 4, 5}.unite({1, 4, 3, 9});
  EXPECT_EQ(u.x0, 1);
  EXPECT_EQ(u.y1, 9);
  const CellWindow g = u.grown(3, 6, 20);
  EXPECT_EQ(g.x0, 0);
  EXPECT_EQ(g.x1, 6);
  EXPECT_EQ(g.y0, 0);
  EXPECT_EQ(g.y1, 12);
}

TEST(Footprint, RadiiPaddingAndCollision) {
  const Footprint square{{-0.2, -0.2}, {-0.2, 0.2}, {0.2, 0.2}, {0.2, -0.2}};  // the tutorial's car
  EXPECT_NEAR(inscribedRadius(square), 0.2, 1e-12);
  EXPECT_NEAR(circumscribedRadius(square), 0.2 * std::sqrt(2.0), 1e-12);
  const Footprint padded = padFootprint(square, 0.05);
  EXPECT_NEAR(circumscribedRadius(padded), 0.2 * std::sqrt(2.0) + 0.05, 1e-12);
  const Footprint circle = circleFootprint(0.2);
  EXPECT_NEAR(inscribedRadius(circle), 0.2, 1e-9);
  EXPECT_THROW(validateFootprint({{1, 1}, {2, 1}, {2, 2}}), std::invalid_argument);  // centre outside
  EXPECT_NO_THROW(validateFootprint(square));

  Costmap m(100, 100, 0.05, {0, 0});
  for (int y = 0; y < 100; ++y) m.setCost({70, y}, cost::kLethal);  // a wall at x = 3.5 m
  EXPECT_EQ(footprintCost(m, {2.5, 2.5, 0.0}, square), 0);
  EXPECT_EQ(footprintCost(m, {3.35, 2.5, 0.0}, square), -1);  // the front edge reaches the wall
  // Turned 45 degrees, the corner reaches further: 0.28 m instead of 0.2 m.
  EXPECT_EQ(footprintCost(m, {3.25, 2.5, 0.0}, square), 0);
  EXPECT_EQ(footprintCost(m, {3.25, 2.5, M_PI / 4}, square), -1);
  EXPECT_EQ(footprintCost(m, {0.1, 2.5, 0.0}, square), -1);  // partly off the map
}

TEST(Footprint, AnOutlineNearAWallCornerSeesTheCornerCell) {
  // A wall ends in the lethal cell (42, 52) of a 5 cm grid. The footprint's edge from (2.17, 2.61)
  // in cell (43, 52) to (2.11, 2.663) in cell (42, 53) crosses that cell near its corner, where
  // Bresenham's walk between the two corner cells steps diagonally past it.
  Costmap m(100, 100, 0.05, {0, 0});
  m.setCost({42, 52}, cost::kLethal);
  const Eigen::Vector3d pose(2.3, 2.75, 0.0);
  const Footprint quad{{-0.13, -0.14}, {-0.19, -0.087}, {0.1, 0.15}, {0.15, -0.1}};
  EXPECT_EQ(footprintCost(m, pose, quad), -1);
  EXPECT_EQ(footprintCost(m, {2.3, 2.8, 0.0}, quad), 0);  // 5 cm further off: clear
}

TEST(Footprint, ARoundRobotCostsTheSameAtEveryHeading) {
  // robot_radius 0.2, padded by 0.01: checked as the circle through its vertices, so that a robot
  // that stands clear beside a wall corner can always turn on the spot (the 16-gon's outline cells
  // change as it turns, and one of them may fall on the corner's cell).
  Costmap m(100, 100, 0.05, {0, 0});
  for (int x = 0; x <= 53; ++x) m.setCost({x, 52}, cost::kLethal);  // a wall ending at (2.7, 2.6..2.65)
  const Footprint round = padFootprint(circleFootprint(0.2), 0.01);
  const double r = circumscribedRadius(round);
  int clear = 0;
  for (double x = 2.6; x < 3.0; x += 0.013) {
    for (double y = 2.25; y < 2.45; y += 0.011) {
      const int first = footprintCost(m, {x, y, 0.0}, round);
      for (int k = 1; k < 64; ++k) ASSERT_EQ(footprintCost(m, {x, y, k * M_PI / 32}, round), first) << x << " " << y;
      // Clear exactly when no lethal cell comes within the circle's radius.
      double nearest = 1e9;
      for (int cx = 0; cx <= 53; ++cx) {
        const double dx = std::max({cx * 0.05 - x, 0.0, x - (cx + 1) * 0.05});
        const double dy = std::max({52 * 0.05 - y, 0.0, y - 53 * 0.05});
        nearest = std::min(nearest, std::hypot(dx, dy));
      }
      EXPECT_EQ(first >= 0, nearest >= r) << x << " " << y << " nearest " << nearest;
      clear += first >= 0;
    }
  }
  EXPECT_GT(clear, 0);
  EXPECT_LT(clear, 19 * 31);
}

TEST(Inflation, AFootprintCentredBelowTheContactCostNeverTouchesALethalCell) {
  // What the global planner (lethal_cost) and the local planner (footprintCost) must agree on: a
  // centre the plan may cross is one where the footprint is clear. The inscribed cost (253) alone
  // is not enough: a lethal cell whose centre is farther than the inscribed radius can still reach
  // into the footprint, and a plan through such cells is one the local planner cannot follow.
  // A round footprint (robot_radius), clear at every heading; a polygon's corners reach farther
  // than its inscribed circle, and whether they touch depends on the heading: that is the local
  // planner's to find.
  for (const Footprint& fp : {padFootprint(circleFootprint(0.2), 0.01), padFootprint(circleFootprint(0.3), 0.0)}) {
    InflationParams p;
    p.inscribed_radius = inscribedRadius(fp);
    p.inflation_radius = 0.6;
    p.cost_scaling_factor = 10.0;
    const uint8_t contact = contactCost(p, 0.05, contactRadius(fp));
    ASSERT_LT(contact, cost::kInscribed) << "the contact band lies outside the inscribed one";
    int touching_below_inscribed = 0;
    for (unsigned seed = 1; seed <= 5; ++seed) {
      std::srand(seed);
      Costmap m(80, 80, 0.05, {0, 0});
      for (int k = 0; k < 40; ++k) m.setCost({10 + std::rand() % 60, 10 + std::rand() % 60}, cost::kLethal);
      inflate(m, p);
      for (int y = 10; y < 70; ++y) {
        for (int x = 10; x < 70; ++x) {
          const uint8_t c = m.cost({x, y});
          const Eigen::Vector2d centre = m.cellCenter({x, y});
          for (double yaw : {0.0, 0.4, M_PI / 4, 1.2}) {
            const bool clear = footprintCost(m, {centre.x(), centre.y(), yaw}, fp) >= 0;
            if (c < contact) ASSERT_TRUE(clear) << "cost " << int(c) << " below the contact cost " << int(contact) << " at " << x << ", " << y;
            if (c >= contact && c < cost::kInscribed && !clear) ++touching_below_inscribed;
          }
        }
      }
    }
    EXPECT_GT(touching_below_inscribed, 0) << "no cell below 253 touched: the test shows nothing";
  }
}

#include "mbot_slam_navigation/core/obstacle_layer.h"

namespace {
LaserScan fan(std::vector<float> ranges, double range_max = 5.0) {
  LaserScan s;
  s.angle_min_rad = 0.0;
  s.angle_increment_rad = M_PI / 2;  // east, north, west, south
  s.range_min_m = 0.1;
  s.range_max_m = range_max;
  s.ranges_m = std::move(ranges);
  return s;
}
}  // namespace

TEST(ObstacleLayer, MarksWithinObstacleRangeAndClearsByRayTracing) {
  Costmap layer(100, 100, 0.05, {-2.5, -2.5}, cost::kNoInformation);
  ObservationSourceParams p;  // obstacle_range 2.5, raytrace_range 3.0
  const float inf = std::numeric_limits<float>::infinity();
  // A box placed 1 m east, then moved away: the first scan marks it, the second clears it.
  EXPECT_EQ(updateWithScan(layer, {0, 0, 0}, fan({1.0f, inf, std::nanf(""), 2.6f}), p), 1);
  const Cell box = layer.worldToCell({1.0, 0.0});
  EXPECT_EQ(layer.cost(box), cost::kLethal);
  EXPECT_EQ(layer.cost(layer.worldToCell({0.5, 0.0})), cost::kFree);          // cleared before it
  EXPECT_EQ(layer.cost(layer.worldToCell({0.0, 2.0})), cost::kFree);          // +inf clears north...
  EXPECT_EQ(layer.cost(layer.worldToCell({-1.0, 0.0})), cost::kNoInformation);  // NaN beam: nothing
  EXPECT_EQ(layer.cost(layer.worldToCell({0.0, -1.0})), cost::kFree);         // 2.6 m south: beyond obstacle_range,
  for (int y = 0; y < 100; ++y) EXPECT_NE(layer.cost({50, y}), y == 50 ? 255 : cost::kLethal);  // cleared, not marked
  updateWithScan(layer, {0, 0, 0}, fan({2.0f, inf, inf, inf}), p);
  EXPECT_EQ(layer.cost(box), cost::kFree);
  EXPECT_EQ(layer.cost(layer.worldToCell({2.0, 0.0})), cost::kLethal);
}

TEST(ObstacleLayer, ClearingStopsAtRaytraceRange) {
  Costmap layer(200, 10, 0.05, {-0.5, -0.25}, cost::kLethal);
  ObservationSourceParams p;
  p.raytrace_range = 1.0;
  p.obstacle_range = 0.5;
  updateWithScan(layer, {0, 0, 0}, fan({4.0f}), p);
  EXPECT_EQ(layer.cost(layer.worldToCell({0.9, 0.0})), cost::kFree);
  EXPECT_EQ(layer.cost(layer.worldToCell({1.2, 0.0})), cost::kLethal);  // beyond raytrace_range: kept
  EXPECT_EQ(layer.cost(layer.worldToCell({4.0, 0.0})), cost::kLethal);  // not marked anew, not cleared
}

TEST(ObstacleLayer, ReturnsScatteredAcrossACellBorderDoNotEraseEachOther) {
  // A wall 1.0 m east whose face lies on a cell border: with the laser's noise, one scan's return
  // falls just short of the border, the next one's just past it. The second beam passes the first
  // return's cell within the noise of its end: that cell keeps its mark (raytrace_end_margin), and
  // the wall stays one surface instead of flickering between the two cells. costmap_2d's rule
  // (margin 0) erases it.
  for (double margin : {0.03, 0.0}) {
    Costmap layer(100, 100, 0.05, {-2.5, -2.5}, cost::kNoInformation);
    ObservationSourceParams p;
    p.raytrace_end_margin = margin;
    updateWithScan(layer, {0, 0, 0}, fan({0.995f}), p);
    const Cell near = layer.worldToCell({0.995, 0.0}), far = layer.worldToCell({1.005, 0.0});
    ASSERT_NE(near.x, far.x);
    updateWithScan(layer, {0, 0, 0}, fan({1.005f}), p);
    EXPECT_EQ(layer.cost(far), cost::kLethal);
    EXPECT_EQ(layer.cost(near), margin > 0.0 ? cost::kLethal : cost::kFree) << "margin " << margin;
    // Farther from the new end than the margin, a mark is cleared as before (an obstacle gone).
    updateWithScan(layer, {0, 0, 0}, fan({1.2f}), p);
    EXPECT_EQ(layer.cost(near), cost::kFree);
    EXPECT_EQ(layer.cost(far), cost::kFree);
    EXPECT_EQ(layer.cost(layer.worldToCell({0.5, 0.0})), cost::kFree);
  }
}

TEST(ObstacleLayer, MinusInfinityMarksRangeMinAndDriverErrorCodesDoNothing) {
  // A person covers the laser: REP 117's -inf (nearer than range_min). It is marked at range_min
  // along the beam, so the costmap has it where the robot is; a finite reading below range_min (a
  // driver's error code) marks nothing; a later return beyond it clears the mark.
  Costmap layer(100, 100, 0.05, {-2.5, -2.5}, cost::kNoInformation);
  ObservationSourceParams p;
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(updateWithScan(layer, {0, 0, 0}, fan({-inf, 0.02f, std::nanf(""), -inf}), p), 2);
  EXPECT_EQ(layer.cost(layer.worldToCell({0.1, 0.0})), cost::kLethal);    // east, -inf
  EXPECT_EQ(layer.cost(layer.worldToCell({0.0, -0.1})), cost::kLethal);   // south, -inf
  EXPECT_EQ(layer.cost(layer.worldToCell({0.0, 0.1})), cost::kNoInformation);  // north, 0.02 m: nothing
  updateWithScan(layer, {0, 0, 0}, fan({1.0f, inf, inf, inf}), p);
  EXPECT_EQ(layer.cost(layer.worldToCell({0.1, 0.0})), cost::kFree);      // the person left
  EXPECT_EQ(layer.cost(layer.worldToCell({0.0, -0.1})), cost::kFree);
  // costmap_2d's way, on request: -inf is dropped.
  Costmap ros_way(100, 100, 0.05, {-2.5, -2.5}, cost::kNoInformation);
  p.too_close_is_obstacle = false;
  EXPECT_EQ(updateWithScan(ros_way, {0, 0, 0}, fan({-inf, -inf, -inf, -inf}), p), 0);
}

namespace {
/// A scan from `at` (x, y, yaw) of discs (x, y, radius), 720 beams over 360 degrees, exact ranges.
LaserScan scanOfDiscs(const Eigen::Vector3d& at, const std::vector<Eigen::Vector3d>& discs) {
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = 2 * M_PI / 720;
  s.range_min_m = 0.1;
  s.range_max_m = 6.0;
  for (int i = 0; i < 720; ++i) {
    const double a = at.z() + s.angle_min_rad + i * s.angle_increment_rad;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    float r = std::numeric_limits<float>::infinity();
    for (const auto& c : discs) {
      const Eigen::Vector2d o = at.head<2>() - c.head<2>();
      const double b = o.dot(d), q = o.squaredNorm() - c.z() * c.z(), disc = b * b - q;
      if (disc >= 0 && -b - std::sqrt(disc) > 0) r = std::min(r, static_cast<float>(-b - std::sqrt(disc)));
    }
    s.ranges_m.push_back(r);
  }
  return s;
}
}  // namespace

TEST(CellBoxes, AMarkKeepsTheBoxOfItsReturnsAndAMapCellStaysWhole) {
  Costmap layer(40, 40, 0.05, {0, 0});
  layer.enableBoxes();
  ObservationSourceParams p;
  // One disc seen from two sides: its cells' boxes hold what each side saw, inside the cell.
  const std::vector<Eigen::Vector3d> disc = {{1.0, 1.0, 0.1}};
  updateWithScan(layer, {0.4, 1.0, 0.0}, scanOfDiscs({0.4, 1.0, 0.0}, disc), p);
  updateWithScan(layer, {1.6, 1.0, M_PI}, scanOfDiscs({1.6, 1.0, M_PI}, disc), p);
  int marked = 0;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      if (layer.cost({x, y}) != cost::kLethal) continue;
      ++marked;
      const uint32_t b = layer.box(layer.index({x, y}));
      ASSERT_NE(b, cell_box::kNoBox);
      // Every corner of the box lies within 1 cm (the margin) of the disc's circle or inside it.
      const Eigen::Vector4d r = layer.obstacleBounds({x, y}, 0.0);
      const Eigen::Vector2d centre(1.0, 1.0);
      const double nearest = std::hypot(std::max({r[0] - 1.0, 0.0, 1.0 - r[2]}), std::max({r[1] - 1.0, 0.0, 1.0 - r[3]}));
      EXPECT_LE(nearest, 0.1 + 1e-3) << "box of cell " << x << ", " << y << " lies off the disc";
      EXPECT_LT(r[2] - r[0], 0.05) << "a box as wide as its cell at " << x << ", " << y;
    }
  }
  EXPECT_GT(marked, 6);
  // The disc taken away (a person who walked on): the beams through its cells clear them all,
  // small boxes or not.
  Costmap gone = layer;
  updateWithScan(gone, {0.4, 1.0, 0.0}, scanOfDiscs({0.4, 1.0, 0.0}, {}), p);
  updateWithScan(gone, {1.6, 1.0, M_PI}, scanOfDiscs({1.6, 1.0, M_PI}, {}), p);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) EXPECT_NE(gone.cost({x, y}), cost::kLethal) << "a mark left at " << x << ", " << y;
  }
  // The whole grid filled again: no box outlives its mark.
  layer.fill(cost::kLethal);
  EXPECT_EQ(layer.box(layer.index({20, 20})), cell_box::kNoBox);
}

TEST(CellBoxes, AGapJustWiderThanTheRobotIsOpenToTheLaserAndShutToWholeCells) {
  // Two posts (radius 0.1 m) whose surfaces are 0.46 m apart (1.15x the mbot's 0.4 m), seen from
  // before the gap, and the padded mbot (0.42 m) in the gap's middle facing through it. Whole
  // 0.05 m cells round the gap to 0.36-0.46 m: with the posts' surfaces near the middle of their
  // cells it is shut, to the footprint check and to the planner's contact cost. With the boxes of
  // the returns it is open to both; a gap the robot does not fit (0.40 m) stays shut.
  const Footprint fp = padFootprint({{-0.2, -0.2}, {-0.2, 0.2}, {0.2, 0.2}, {0.2, -0.2}}, 0.01);
  InflationParams ip;
  ip.inscribed_radius = inscribedRadius(fp);
  ip.inflation_radius = 0.6;
  ip.cost_scaling_factor = 10.0;
  const double contact_radius = contactRadius(fp);
  const uint8_t contact = contactCost(ip, 0.05, contact_radius);
  for (double gap : {0.46, 0.40}) {
    // Centred on a cell's edge at y = 1.5 m, so each surface lies mid-cell (1.5 -/+ gap / 2).
    const double y = 1.5, r = 0.1;
    const std::vector<Eigen::Vector3d> posts = {{1.5, y - gap / 2 - r, r}, {1.5, y + gap / 2 + r, r}};
    for (bool boxes : {false, true}) {
      Costmap layer(60, 60, 0.05, {0, 0});
      if (boxes) layer.enableBoxes();
      ObservationSourceParams p;
      for (double x0 : {0.5, 0.8, 1.0}) updateWithScan(layer, {x0, y, 0.0}, scanOfDiscs({x0, y, 0.0}, posts), p);
      Costmap master = layer;
      inflateWindow(layer, master, {0, 0, 60, 60}, ip);
      refineNearBoxes(layer, master, {0, 0, 60, 60}, ip, contact_radius);
      const Cell mid = master.worldToCell({1.5, y + 0.01});
      const bool planner_open = master.cost(mid) < contact || master.cost(master.worldToCell({1.5, y - 0.01})) < contact;
      const bool footprint_open = footprintCost(master, {1.5, y, 0.0}, fp) >= 0;
      SCOPED_TRACE("gap " + std::to_string(gap) + (boxes ? " with boxes" : " whole cells"));
      EXPECT_EQ(footprint_open, boxes && gap > 0.44);
      EXPECT_EQ(planner_open, boxes && gap > 0.44);
    }
  }
}

TEST(CellBoxes, TheLasersNoiseDoesNotShutAGapOverTime) {
  // Two posts 0.46 m apart and the mbot (radius 0.2 m) in the gap's middle: 3 cm a side, 2 cm
  // beyond the boxes' 1 cm margin. A laser with 1 cm of noise (the simulated Hokuyo's) watches the
  // gap for 10 s (100 scans). A box holds the latest scan's returns, so the gap stays open in most
  // scans; boxes grown by every scan's returns reach out by the largest deviation of hundreds, and
  // shut it for good within a few seconds.
  const Footprint fp = circleFootprint(0.2);
  const double y = 1.5, r = 0.1, gap = 0.46;
  const std::vector<Eigen::Vector3d> posts = {{1.5, y - gap / 2 - r, r}, {1.5, y + gap / 2 + r, r}};
  const Eigen::Vector3d laser(1.5, y, 0.0);
  Costmap layer(60, 60, 0.05, {0, 0});
  layer.enableBoxes();
  ObservationSourceParams p;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  int open = 0, open_late = 0;
  for (int k = 0; k < 100; ++k) {
    LaserScan scan = scanOfDiscs(laser, posts);
    for (float& range : scan.ranges_m) {
      if (std::isfinite(range)) range += static_cast<float>(noise(rng));
    }
    updateWithScan(layer, laser, scan, p);
    const bool is_open = footprintCost(layer, {1.5, y, 0.0}, fp) >= 0;
    open += is_open;
    if (k >= 50) open_late += is_open;
  }
  EXPECT_GE(open, 80);
  EXPECT_GE(open_late, 40) << "the gap shut as the scans went on";
}

TEST(CellBoxes, AFootprintInACellBelowTheContactCostFitsWithoutTouchingABox) {
  // The rule of Inflation.AFootprintCentredBelowTheContactCostNeverTouchesALethalCell, for cells
  // whose obstacles are boxes of random size and place, among whole cells: below the contact cost
  // the footprint fits somewhere in the cell (refineNearBoxes takes the best of 3 x 3 points).
  const Footprint fp = padFootprint(circleFootprint(0.2), 0.01);
  InflationParams p;
  p.inscribed_radius = inscribedRadius(fp);
  p.inflation_radius = 0.6;
  p.cost_scaling_factor = 10.0;
  const uint8_t contact = contactCost(p, 0.05, contactRadius(fp));
  int open_cells = 0;  // cells below the contact cost that whole cells would have put above it
  for (unsigned seed = 1; seed <= 5; ++seed) {
    std::srand(seed);
    Costmap base(80, 80, 0.05, {0, 0});
    base.enableBoxes();
    for (int k = 0; k < 40; ++k) {
      const Cell c{10 + std::rand() % 60, 10 + std::rand() % 60};
      base.setCost(c, cost::kLethal);
      if (k % 4 == 0) continue;  // a whole cell
      const int x0 = std::rand() % 200, y0 = std::rand() % 200;
      base.setBox(base.index(c), cell_box::pack(x0, y0, x0 + 1 + std::rand() % (254 - x0), y0 + 1 + std::rand() % (254 - y0)));
    }
    Costmap whole = base, master = base;
    inflate(whole, p);
    inflateWindow(base, master, {0, 0, 80, 80}, p);
    refineNearBoxes(base, master, {0, 0, 80, 80}, p, contactRadius(fp));
    for (int y = 10; y < 70; ++y) {
      for (int x = 10; x < 70; ++x) {
        const uint8_t c = master.cost({x, y});
        const Eigen::Vector2d centre = master.cellCenter({x, y});
        if (c < contact) {
          bool clear = false;  // somewhere in the cell: one of its 3 x 3 points
          for (int k = 0; k < 9 && !clear; ++k) {
            const Eigen::Vector2d at = centre + Eigen::Vector2d(k % 3 - 1, k / 3 - 1) * (0.05 / 3.0);
            clear = footprintCost(master, {at.x(), at.y(), 0.0}, fp) >= 0;
          }
          ASSERT_TRUE(clear) << "cost " << int(c) << " below the contact cost " << int(contact) << " at " << x << ", " << y;
          open_cells += whole.cost({x, y}) >= contact;
        }
      }
    }
  }
  EXPECT_GT(open_cells, 0) << "the boxes opened nothing: the test shows nothing";
}
