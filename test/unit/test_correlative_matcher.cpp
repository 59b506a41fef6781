#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/cell.h"
#include "mbot_slam_navigation/core/correlative_matcher.h"
#include "mbot_slam_navigation/core/pose2d.h"
#include "mbot_slam_navigation/core/world2d.h"

using namespace mbot::core;

namespace {
// An L-shaped room with a pillar: every pose dimension is observable.
World2D room() {
  World2D w;
  w.addBox({0, 4.05}, 0, 10.2, 0.1);
  w.addBox({0, -4.05}, 0, 10.2, 0.1);
  w.addBox({5.05, 0}, 0, 0.1, 8.2);
  w.addBox({-5.05, 0}, 0, 0.1, 8.2);
  w.addBox({2.5, 2.0}, 0, 5.0, 4.0);
  w.addCylinder({-2.0, -1.0}, 0.4);
  w.addBox({-3.5, 2.5}, 0.3, 0.8, 0.5);
  return w;
}

LaserScan scanAt(const World2D& w, const Eigen::Vector3d& pose, std::mt19937& rng, double noise) {
  LaserScan s;
  s.angle_min_rad = -M_PI;
  s.angle_increment_rad = M_PI / 180;
  s.range_min_m = 0.1;
  s.range_max_m = 12.0;
  s.ranges_m.resize(360);
  w.castScan(pose, s.angle_min_rad, s.angle_increment_rad, 360, 0.1, 12.0, noise, 0.0, rng, s.ranges_m.data());
  return s;
}

std::vector<Eigen::Vector2d> inWorld(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector3d& pose) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : pts) out.push_back(composePose(pose, {p.x(), p.y(), 0.0}).head<2>());
  return out;
}
}  // namespace

TEST(CorrelativeMatcher, BranchAndBoundFindsTheExhaustiveOptimum) {
  const World2D w = room();
  std::mt19937 rng(3);
  const Eigen::Vector3d ref(-1.0, 0.5, 0.3), truth(-0.6, 0.2, 0.45);
  const LikelihoodGrid grid(inWorld(matchPoints(scanAt(w, ref, rng, 0.01), Eigen::Vector3d::Zero(), 11.0, 0.05), ref),
                            0.05, 0.05);
  const auto points = matchPoints(scanAt(w, truth, rng, 0.01), Eigen::Vector3d::Zero(), 11.0, 0.05);
  const Eigen::Vector3d init(truth.x() + 0.17, truth.y() - 0.12, truth.z() + 0.08);
  const MatchWindow window{0.3, 0.12};
  const MatchResult bb = matchBranchAndBound(grid, points, init, window, 0.0);
  ASSERT_TRUE(bb.found);

  // Exhaustive search over the same lattice: the same angles and whole-cell offsets.
  double dmax = 0;
  for (const auto& p : points) dmax = std::max(dmax, p.norm());
  const double astep = std::acos(1.0 - 0.05 * 0.05 / (2 * dmax * dmax));
  const int na = static_cast<int>(std::ceil(window.angular_rad / astep)), wl = 6;
  int best = -1;
  for (int a = -na; a <= na; ++a) {
    const double yaw = init.z() + a * astep;
    for (int ox = -wl; ox <= wl; ++ox) {
      for (int oy = -wl; oy <= wl; ++oy) {
        int sum = 0;
        for (const auto& p : points) {
          const Eigen::Vector2d q = composePose({init.x(), init.y(), yaw}, {p.x(), p.y(), 0}).head<2>();
          const Cell c = worldToCell(grid.origin(), 0.05, q);
          sum += grid.value(c.x + ox, c.y + oy);
        }
        best = std::max(best, sum);
      }
    }
  }
  EXPECT_NEAR(bb.score, best / (LikelihoodGrid::kMax * points.size()), 1e-9);
  EXPECT_LT((bb.pose.head<2>() - truth.head<2>()).norm(), 0.06);
  EXPECT_LT(std::abs(normalizeAngle(bb.pose.z() - truth.z())), 0.02);

  double score = 0;
  const Eigen::Vector3d refined = refineMatch(grid, points, bb.pose, 0.005, 4, &score);
  EXPECT_GE(score, grid.score(points, bb.pose));
  EXPECT_LT((refined.head<2>() - truth.head<2>()).norm(), 0.03);
  EXPECT_LT(std::abs(normalizeAngle(refined.z() - truth.z())), 0.01);
}

TEST(CorrelativeMatcher, FindsALargeOffsetAndRespectsTheMinimumAndExclusion) {
  const World2D w = room();
  std::mt19937 rng(5);
  const Eigen::Vector3d truth(-2.5, 1.0, -0.4);
  std::vector<Eigen::Vector2d> ref;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-3, 1, 0), Eigen::Vector3d(0, -2, 1.5), Eigen::Vector3d(3, -2, 3)}) {
    const auto pts = inWorld(matchPoints(scanAt(w, p, rng, 0.0), Eigen::Vector3d::Zero(), 11.0, 0.05), p);
    ref.insert(ref.end(), pts.begin(), pts.end());
  }
  const LikelihoodGrid grid(ref, 0.05, 0.05);
  const auto points = matchPoints(scanAt(w, truth, rng, 0.01), Eigen::Vector3d::Zero(), 11.0, 0.05);
  // 2.1 m and 0.3 rad off: a loop closure's search, not a tracking one.
  const Eigen::Vector3d init(truth.x() + 1.5, truth.y() - 1.5, truth.z() + 0.3);
  const MatchResult r = matchBranchAndBound(grid, points, init, {2.5, 0.4}, 0.5);
  ASSERT_TRUE(r.found);
  EXPECT_GT(r.score, 0.6);
  EXPECT_LT((r.pose.head<2>() - truth.head<2>()).norm(), 0.06);
  EXPECT_LT(std::abs(normalizeAngle(r.pose.z() - truth.z())), 0.02);
  // No pose in a window that excludes the truth reaches the minimum.
  EXPECT_FALSE(matchBranchAndBound(grid, points, init, {0.5, 0.1}, 0.5).found);
  // Nothing else in the room explains the scan nearly as well.
  EXPECT_FALSE(matchBranchAndBound(grid, points, init, {2.5, 0.4}, 0.9 * r.score, &r.pose, 0.3, 0.1).found);
}

TEST(CorrelativeMatcher, PointsSkipInvalidAndFarReturnsAndThinOut) {
  LaserScan s;
  s.angle_min_rad = 0.0;
  s.angle_increment_rad = 0.001;
  s.range_min_m = 0.2;
  s.range_max_m = 30.0;
  s.ranges_m = {1.02f, 1.02f, NAN, INFINITY, -INFINITY, 0.1f, 25.0f, 3.0f};
  const auto pts = matchPoints(s, Eigen::Vector3d(0.1, 0, 0), 20.0, 0.05);
  ASSERT_EQ(pts.size(), 2u);  // the two 1 m beams fall in one cell; 25 m is beyond 20 m
  EXPECT_NEAR(pts[0].x(), 1.12, 1e-6);
  EXPECT_NEAR(pts[1].norm(), 3.1, 0.01);
}

TEST(CorrelativeMatcher, RejectsBadGridParameters) {
  EXPECT_THROW(LikelihoodGrid({}, 0.0, 0.05), std::invalid_argument);
  EXPECT_THROW(LikelihoodGrid({}, 0.05, -1.0), std::invalid_argument);
}

TEST(CorrelativeMatcher, SurfacePointsFillAWallSeenAtAGrazingAngleButNotAGapBehindAnEdge) {
  // Beams 1 degree apart from the origin: 0..9 on a wall along y = 1 seen at 20-29 degrees (hits
  // 0.06-0.14 m apart), 10..14 on a wall 3 m farther (a depth jump of metres: never filled).
  LaserScan s;
  s.angle_min_rad = 0.35;
  s.angle_increment_rad = M_PI / 180.0;
  s.range_min_m = 0.1;
  s.range_max_m = 20.0;
  for (int i = 0; i < 10; ++i) s.ranges_m.push_back(1.0 / std::sin(s.angle_min_rad + i * s.angle_increment_rad));
  for (int i = 10; i < 15; ++i) s.ranges_m.push_back(3.0 + 1.0 / std::sin(s.angle_min_rad + i * s.angle_increment_rad));
  const auto hits = matchPoints(s, Eigen::Vector3d::Zero(), 20.0, 0.05);
  const auto surface = surfacePoints(s, Eigen::Vector3d::Zero(), 20.0, 0.05);
  ASSERT_EQ(hits.size(), 15u);
  EXPECT_GT(surface.size(), hits.size() + 10);
  double widest_on_wall = 0.0;
  std::vector<double> xs;
  for (const auto& p : surface) {
    EXPECT_TRUE(std::abs(p.y() - 1.0) < 0.02 || p.norm() > 3.5) << "a filled point off both surfaces: " << p.transpose();
    if (std::abs(p.y() - 1.0) < 0.02) xs.push_back(p.x());
  }
  std::sort(xs.begin(), xs.end());
  for (std::size_t i = 1; i < xs.size(); ++i) widest_on_wall = std::max(widest_on_wall, xs[i] - xs[i - 1]);
  EXPECT_LE(widest_on_wall, 0.1) << "the wall seen at a grazing angle should be continuous (hits alone: 0.14 m apart)";
}

TEST(CorrelativeMatcher, TheInterpolatedScorePeaksOnAWallThatLiesOnACellBorder) {
  // A wall along y = 1.0, the border between two rows of 0.05 m cells: bilinear interpolation is
  // flat between the two cell centres (0.975 and 1.025), so a scan could sit 2.5 cm off at no cost.
  std::vector<Eigen::Vector2d> wall;
  for (double x = 0.0; x <= 2.0; x += 0.05) wall.emplace_back(x, 1.0);
  const LikelihoodGrid grid(wall, 0.05, 0.075);
  const double on = grid.interpolated({1.0, 1.0});
  EXPECT_GT(on, grid.interpolated({1.0, 0.985}) + 0.005);
  EXPECT_GT(on, grid.interpolated({1.0, 1.015}) + 0.005);
  EXPECT_NEAR(grid.interpolated({1.0, 0.985}), grid.interpolated({1.0, 1.015}), 1e-3);
}

TEST(CorrelativeMatcher, CellsTellDistancesOfAMillimetreNearAPoint) {
  // exp(-d^2 / 2 sigma^2) stored as 0..255 stays 255 while d < 0.066 sigma (5 mm for the default
  // 0.075 m kernel): every cell centre within 5 mm of a wall scored the same, whatever its distance.
  const double res = 0.05, sigma = 0.075;
  for (double d_mm : {1.0, 2.0, 3.0, 4.0}) {
    // A point d_mm and one (d_mm + 1) mm from the centre of cell (3, 3) of grids laid out alike.
    const Eigen::Vector2d centre(3.5 * res, 3.5 * res);
    const LikelihoodGrid near({centre + Eigen::Vector2d(1e-3 * d_mm, 0)}, res, sigma);
    const LikelihoodGrid far({centre + Eigen::Vector2d(1e-3 * (d_mm + 1.0), 0)}, res, sigma);
    const Cell c = worldToCell(near.origin(), res, centre);
    ASSERT_EQ(worldToCell(far.origin(), res, centre), c);
    EXPECT_GT(near.value(c.x, c.y), far.value(c.x, c.y)) << d_mm << " mm against " << d_mm + 1.0 << " mm";
  }
}

TEST(CorrelativeMatcher, EachPooledLevelHoldsTheMaximumOfItsBlockAndCellsTheKernel) {
  // The branch and bound's bounds are only bounds if every pooled value is the largest level-0
  // value of its block (the pyramid is built two halves at a time); a cell holds the largest
  // kernel value exp(-d^2 / 2 sigma^2) of the points near it, rounded to the grid's integers.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 12; ++i) points.emplace_back(u(rng), 0.5 * u(rng));
  const double res = 0.05, sigma = 0.075;
  const LikelihoodGrid grid(points, res, sigma);
  const int r = static_cast<int>(std::ceil(3.0 * sigma / res));  // the kernel's reach [cells] each way
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      double best = 0.0;
      for (const auto& p : points) {
        const Cell c = worldToCell(grid.origin(), res, p);
        if (std::abs(c.x - x) > r || std::abs(c.y - y) > r) continue;
        const double d = (cellCenter(grid.origin(), res, {x, y}) - p).norm();
        best = std::max(best, std::exp(-d * d / (2.0 * sigma * sigma)));
      }
      ASSERT_NEAR(grid.value(x, y), LikelihoodGrid::kMax * best, 1.0) << "cell " << x << ", " << y;
    }
  }
  grid.buildLevels(5);
  for (int h = 1; h < 5; ++h) {
    const int side = 1 << h;
    for (int y = -side + 1; y < grid.height(); ++y) {
      for (int x = -side + 1; x < grid.width(); ++x) {
        int best = 0;
        for (int dy = 0; dy < side; ++dy)
          for (int dx = 0; dx < side; ++dx) best = std::max(best, grid.value(x + dx, y + dy));
        ASSERT_EQ(grid.pooled(h, x, y), best) << "level " << h << " at " << x << ", " << y;
      }
    }
    EXPECT_EQ(grid.pooled(h, grid.width(), 0), 0);  // outside the level
    EXPECT_EQ(grid.pooled(h, -side, 0), 0);
  }
}

TEST(CorrelativeMatcher, SurfaceNormalsFaceTheLaserAndAreUnknownAtEdges) {
  // A wall along y = 1 seen from the origin, then one point 1 m off it (a depth edge).
  std::vector<Eigen::Vector2d> pts;
  for (double x = -0.5; x <= 0.51; x += 0.05) pts.emplace_back(x, 1.0);
  pts.emplace_back(1.5, 2.0);
  const auto n = surfaceNormals(pts, {0.0, 0.0}, 0.3);
  ASSERT_EQ(n.size(), pts.size());
  EXPECT_TRUE(n.front().isZero()) << "an end has one neighbour";
  for (std::size_t i = 1; i + 2 < pts.size(); ++i) {
    EXPECT_NEAR(n[i].x(), 0.0, 1e-9) << i;
    EXPECT_NEAR(n[i].y(), -1.0, 1e-9) << i << ": towards the laser";
  }
  EXPECT_TRUE(n[pts.size() - 2].isZero()) << "its next neighbour lies 1.1 m off: an edge";
  EXPECT_TRUE(n.back().isZero());
  // Seen from the other side, the same wall faces the other way.
  EXPECT_NEAR(surfaceNormals(pts, {0.0, 3.0}, 0.3)[5].y(), 1.0, 1e-9);
}

TEST(CorrelativeMatcher, VisibilityTellsAWallsFaceFromTheFaceBehindIt) {
  // A wall 0.1 m thick across x = 3.0 .. 3.1, seen by one scan from the origin (its west face).
  // A scan from beyond it, at (6, 0), sees the east face 0.1 m behind: within a tolerance that a
  // pose a few centimetres off needs, but not a face that scan saw.
  World2D w;
  w.addBox({3.05, 0}, 0, 0.1, 2.0);
  std::mt19937 rng(3);
  const Eigen::Vector3d pose(0.0, 0.0, 0.0), laser(0.0, 0.0, 0.0);
  const LaserScan s = scanAt(w, pose, rng, 0.0);
  Visibility v;
  v.add(s, laser, pose, 5.0);
  const Eigen::Vector2d west(-1.0, 0.0), east(1.0, 0.0);  // each face's normal, towards its viewer
  EXPECT_TRUE(v.seen({3.0, 0.5}, 0.15, &west)) << "the face it saw";
  EXPECT_TRUE(v.seen({3.1, 0.5}, 0.15)) << "the other face, within the tolerance";
  EXPECT_FALSE(v.seen({3.1, 0.5}, 0.15, &east)) << "the other face, seen from beyond the wall";
  EXPECT_TRUE(v.seen({2.0, 0.3}, 0.15, &west)) << "in the open, a surface facing the scan";
  EXPECT_FALSE(v.seen({2.0, 0.3}, 0.15, &east)) << "in the open, a surface facing away from it";
  // The same through seenOf, in the frame of a base at (6, 0) facing -x.
  const std::vector<Eigen::Vector2d> points{{2.9, -0.5}, {2.9, -0.55}, {2.9, -0.6}};
  const auto normals = surfaceNormals(points, {0.0, 0.0}, 0.3);
  EXPECT_EQ(v.seenOf(points, {6.0, 0.0, M_PI}, 0.15).size(), 3u);
  EXPECT_EQ(v.seenOf(points, {6.0, 0.0, M_PI}, 0.15, &normals).size(), 2u) << "the middle one has a side; the ends do not";
}

TEST(CorrelativeMatcher, TheOtherFaceOfAWallTheScansSawIsLeftOutOfAScanFromBeyondIt) {
  // A wall 0.1 m thick across x = 3.0 .. 3.1, seen by one scan from the origin (its west face). A
  // scan from (4, 0) facing -x, just through a door, sees the east face 0.1 m behind the face the
  // scan saw, and a wall at x = 5.5 behind itself that no scan saw.
  World2D w;
  w.addBox({3.05, 0}, 0, 0.1, 2.0);
  w.addBox({5.55, 0}, 0, 0.1, 2.0);
  std::mt19937 rng(3);
  Visibility v;
  v.add(scanAt(w, Eigen::Vector3d::Zero(), rng, 0.0), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 12.0);
  const Eigen::Vector3d pose(4.0, 0.0, M_PI);
  const auto points = matchPoints(scanAt(w, pose, rng, 0.0), Eigen::Vector3d::Zero(), 11.0, 0.05);
  const auto normals = surfaceNormals(points, Eigen::Vector2d::Zero(), 0.3);
  const auto kept = v.notBehindOf(points, pose, 0.05, 0.25, normals);
  int east_face = 0, far_wall = 0, east_face_kept = 0, far_wall_kept = 0;
  auto onEastFace = [&](const Eigen::Vector2d& p) { return std::abs(composePose(pose, {p.x(), p.y(), 0}).x() - 3.1) < 0.02; };
  auto onFarWall = [&](const Eigen::Vector2d& p) { return std::abs(composePose(pose, {p.x(), p.y(), 0}).x() - 5.5) < 0.02; };
  for (const auto& p : points) {
    east_face += onEastFace(p);
    far_wall += onFarWall(p);
  }
  for (const auto& p : kept) {
    east_face_kept += onEastFace(p);
    far_wall_kept += onFarWall(p);
  }
  ASSERT_GT(east_face, 20);
  ASSERT_GT(far_wall, 20);
  // Only the ends of the face, which have no normal, stay.
  EXPECT_LE(east_face_kept, 2) << "of " << east_face << " on the wall's other face";
  EXPECT_EQ(far_wall_kept, far_wall) << "what no scan saw is new, not behind anything";
  // Without normals nothing is left out.
  EXPECT_EQ(v.notBehindOf(points, pose, 0.05, 0.25, {}).size(), points.size());
}

TEST(CorrelativeMatcher, VisibilityKnowsWhatAScanSawAndWhatLayBehindOrBeyond) {
  // The base at the origin facing +y, its laser turned to face +x; a wall 2 m long across x = 3.
  World2D w;
  w.addBox({3.05, 0}, 0, 0.1, 2.0);
  std::mt19937 rng(3);
  const Eigen::Vector3d pose(0.0, 0.0, M_PI / 2), laser(0.0, 0.0, -M_PI / 2);
  LaserScan s = scanAt(w, composePose(pose, laser), rng, 0.0);  // 360 beams from -pi, 12 m
  s.ranges_m[90] = std::numeric_limits<float>::quiet_NaN();  // towards -y: says nothing
  Visibility v;
  EXPECT_TRUE(v.empty());
  v.add(s, laser, pose, 5.0);
  ASSERT_FALSE(v.empty());
  EXPECT_TRUE(v.seen({2.0, 0.0}, 0.05)) << "in front of the wall";
  EXPECT_TRUE(v.seen({3.03, 0.5}, 0.05)) << "on the wall";
  EXPECT_FALSE(v.seen({3.5, 0.0}, 0.05)) << "behind the wall";
  EXPECT_TRUE(v.seen({3.5, 0.0}, 0.6)) << "within the tolerance";
  EXPECT_TRUE(v.seen({0.0, 4.9}, 0.05)) << "no return: free out to the maximum range given";
  EXPECT_FALSE(v.seen({0.0, 5.5}, 0.05)) << "beyond the range given (5 m, not the sensor's 12 m)";
  EXPECT_FALSE(v.seen({0.0, -1.0}, 0.05)) << "the beam with no usable reading";
  EXPECT_TRUE(v.seen({-1.0, 0.007}, 0.05)) << "past the last beam, next to the first: the scan sees all round";
  // Half the circle, ahead of the laser: nothing behind it was seen.
  LaserScan half = s;
  half.angle_min_rad = -M_PI / 2;
  half.ranges_m.assign(s.ranges_m.begin() + 90, s.ranges_m.begin() + 270);
  Visibility front;
  front.add(half, laser, pose, 5.0);
  EXPECT_TRUE(front.seen({2.0, 0.0}, 0.05));
  EXPECT_FALSE(front.seen({-1.0, 0.0}, 0.05)) << "behind a 180 degree laser";
  EXPECT_FALSE(front.seen({-1.0, 0.007}, 0.05)) << "behind a 180 degree laser";
  // Points in the frame of a base at (0.5, 0) facing +x: (1.5, 0) in front, (3, 0) on the wall,
  // (3.5, 0.3) behind it.
  const std::vector<Eigen::Vector2d> points{{1.0, 0.0}, {2.5, 0.0}, {3.0, 0.3}};
  const auto kept = front.seenOf(points, {0.5, 0.0, 0.0}, 0.05);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_DOUBLE_EQ(kept[1].x(), 2.5);
}

TEST(CorrelativeMatcher, TheScoresCurvatureSaysWhichDirectionsAScanFixes) {
  // In the room every direction is fixed; along a plain corridor 2 m wide the score does not curve
  // along it (the scan cannot tell how far the robot went) while across it every return pins it.
  std::mt19937 rng(4);
  const double sigma = 0.075;
  const Eigen::Vector3d pose(-1.0, 0.5, 0.3);
  const auto room_points = matchPoints(scanAt(room(), pose, rng, 0.01), Eigen::Vector3d::Zero(), 11.0, 0.05);
  const LikelihoodGrid room_grid(inWorld(room_points, pose), 0.05, sigma);
  const Eigen::Matrix3d in_room = scoreCurvature(room_grid, room_points, pose);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> room_xy(in_room.topLeftCorner<2, 2>());
  EXPECT_GT(room_xy.eigenvalues().minCoeff() * sigma * sigma, 0.1) << in_room;
  EXPECT_GT(in_room(2, 2), 0.0);

  World2D corridor;
  corridor.addBox({0.0, 1.05}, 0, 60.0, 0.1);
  corridor.addBox({0.0, -1.05}, 0, 60.0, 0.1);
  // The reference as scan tracking builds its local map: walls as surfaces (surfacePoints), from
  // a scan 0.5 m back; hits alone thin out along a wall and would pin the scan to their spacing.
  const Eigen::Vector3d behind(-0.5, 0.2, 0.0), along(0.0, 0.2, 0.0);
  const LikelihoodGrid grid(
      inWorld(surfacePoints(scanAt(corridor, behind, rng, 0.01), Eigen::Vector3d::Zero(), 6.0, 0.05), behind), 0.05,
      sigma);
  const auto points = matchPoints(scanAt(corridor, along, rng, 0.01), Eigen::Vector3d::Zero(), 6.0, 0.05);
  const Eigen::Matrix3d c = scoreCurvature(grid, points, along);
  EXPECT_LT(c(0, 0) * sigma * sigma, 0.02) << c;  // along the corridor: nothing
  EXPECT_GT(c(1, 1) * sigma * sigma, 0.5) << c;   // across it: most returns pin it
  EXPECT_GT(c(2, 2), 0.0) << c;                   // and the heading
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues().minCoeff(), -1e-9);
}

TEST(CorrelativeMatcher, MatchDirectionsFindATurnAroundALonePillar) {
  // A lone pillar 2 m ahead: the score pins the distance and the bearing to it, and x-y alone looks
  // pinned both ways, but a step sideways with a turn the other way (a turn around the pillar)
  // leaves the returns where they were: matchDirections must find that direction open.
  World2D w;
  w.addCylinder({2.0, 0.0}, 0.3);
  std::mt19937 rng(5);
  const double sigma = 0.075;
  const Eigen::Vector3d pose(0.0, 0.0, 0.0);
  const auto points = matchPoints(scanAt(w, pose, rng, 0.0), Eigen::Vector3d::Zero(), 6.0, 0.05);
  ASSERT_GT(points.size(), 5u);
  const LikelihoodGrid grid(
      inWorld(surfacePoints(scanAt(w, pose, rng, 0.0), Eigen::Vector3d::Zero(), 6.0, 0.05), pose), 0.05, sigma);
  const Eigen::Matrix3d c = scoreCurvature(grid, points, pose);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> xy(c.topLeftCorner<2, 2>());
  EXPECT_GT(xy.eigenvalues().minCoeff() * sigma * sigma, 0.1) << "x-y alone looks pinned\n" << c;
  const MatchDirections d = matchDirections(c, points);
  EXPECT_NEAR(d.range_m, 1.7, 0.1);
  // Nearly flat against the other two (the pillar's round face and the turn's centre, the robot,
  // 2 m from it, leave a little).
  EXPECT_LT(d.values[0] * sigma * sigma, 0.1) << d.values.transpose();
  EXPECT_LT(d.values[0], 0.1 * d.values[1]) << d.values.transpose();
  EXPECT_GT(d.values[1] * sigma * sigma, 0.1) << d.values.transpose();
  // The open direction: a step sideways (y) with a turn, in the scaled space.
  const Eigen::Vector3d open = d.vectors.col(0);
  EXPECT_LT(std::abs(open.x()), 0.2) << open.transpose();
  EXPECT_GT(std::abs(open.y()), 0.5) << open.transpose();
  EXPECT_GT(std::abs(open.z()), 0.4) << open.transpose();
  // weighOpen: a step along the open direction is given to the prediction as far as its curvature
  // says; a step along a pinned one is kept.
  const Eigen::Vector3d step_open(open.x(), open.y(), open.z() / d.range_m);
  const Eigen::Vector3d pinned = d.vectors.col(2);
  const Eigen::Vector3d step_pinned(pinned.x(), pinned.y(), pinned.z() / d.range_m);
  const double open_curvature = 0.05 / (sigma * sigma);
  EXPECT_LT(d.weighOpen(0.1 * step_open, open_curvature, 1000.0).norm(), 0.01);
  EXPECT_NEAR((d.weighOpen(0.1 * step_open, open_curvature, 0.0) - 0.1 * step_open).norm(), 0.0, 1e-9);
  EXPECT_NEAR((d.weighOpen(0.1 * step_pinned, open_curvature, 1000.0) - 0.1 * step_pinned).norm(), 0.0, 1e-9);
}
