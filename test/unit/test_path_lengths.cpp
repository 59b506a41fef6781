#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "mbot_slam_navigation/core/path_lengths.h"

using mbot::core::Cell;
using mbot::core::pathLengths;
using mbot::core::pathLengthsBetween;

TEST(PathLengths, OpenGridGivesOctileDistances) {
  std::vector<uint8_t> free(10 * 8, 1);
  const auto d = pathLengths(free, 10, 8, Cell{1, 1});
  EXPECT_FLOAT_EQ(d[1 * 10 + 1], 0.0f);
  EXPECT_FLOAT_EQ(d[1 * 10 + 6], 5.0f);                      // straight along x
  EXPECT_NEAR(d[4 * 10 + 4], 3.0f * std::sqrt(2.0f), 1e-5);  // diagonal
  EXPECT_NEAR(d[7 * 10 + 9], 6.0f * std::sqrt(2.0f) + 2.0f, 1e-5);
}

TEST(PathLengths, WallsMakeTheWayLongerAndClosedRoomsUnreachable) {
  // 9 x 5 grid; a wall at x = 4 with a gap at the top row (y = 4) only.
  const int w = 9, h = 5;
  std::vector<uint8_t> g(w * h, 1);
  for (int y = 0; y < 4; ++y) g[y * w + 4] = 0;
  const auto d = pathLengths(g, w, h, Cell{2, 0});
  // Around through (4, 4): up 4 rows while moving to x = 3, across, back down; no corner cutting at (4, 3).
  EXPECT_GT(d[0 * w + 6], 8.0f);
  EXPECT_LT(d[0 * w + 6], 11.0f);
  EXPECT_EQ(d[0 * w + 4], -1.0f);  // the wall itself
  // Close the gap: the right side becomes unreachable.
  g[4 * w + 4] = 0;
  const auto closed = pathLengths(g, w, h, Cell{2, 0});
  EXPECT_EQ(closed[0 * w + 6], -1.0f);
  EXPECT_GE(closed[4 * w + 0], 0.0f);
}

TEST(PathLengths, DiagonalGapsBetweenBlockedCornersAreClosed) {
  // Two blocked cells touching at a corner: the diagonal between them is not a way through.
  std::vector<uint8_t> g = {1, 0,
                            0, 1};
  const auto d = pathLengths(g, 2, 2, Cell{0, 0});
  EXPECT_EQ(d[3], -1.0f);
}

TEST(PathLengths, StartInsideABlockedCellStillSpreads) {
  std::vector<uint8_t> g(3 * 3, 1);
  g[4] = 0;  // the centre, where the robot stands
  const auto d = pathLengths(g, 3, 3, Cell{1, 1});
  EXPECT_FLOAT_EQ(d[4], 0.0f);
  EXPECT_FLOAT_EQ(d[1], 1.0f);
}

TEST(PathLengths, BadInputIsRefusedWithTheReason) {
  std::vector<uint8_t> g(6, 1);
  EXPECT_THROW(pathLengths(g, 4, 2, Cell{0, 0}), std::invalid_argument);
  EXPECT_THROW(pathLengths(g, 3, 2, Cell{3, 0}), std::invalid_argument);
}

TEST(PathLengthsBetween, MatchesTheFullSearchWhereverTheSearchesStop) {
  // A floor with walls and a closed room; cells near each other and far apart.
  const int w = 60, h = 40;
  std::vector<uint8_t> g(w * h, 1);
  for (int y = 0; y < 30; ++y) g[y * w + 20] = 0;       // a wall with a way round at the top
  for (int x = 40; x < 50; ++x) g[10 * w + x] = g[20 * w + x] = 0;  // a closed room
  for (int y = 10; y <= 20; ++y) g[y * w + 40] = g[y * w + 49] = 0;
  const std::vector<Cell> cells = {{2, 2}, {3, 2}, {30, 5}, {58, 38}, {45, 15}, {2, 2}};
  const auto d = pathLengthsBetween(g, w, h, cells);
  const std::size_t n = cells.size();
  ASSERT_EQ(d.size(), n * n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto full = pathLengths(g, w, h, cells[i]);
    for (std::size_t j = 0; j < n; ++j) {
      EXPECT_DOUBLE_EQ(d[i * n + j], d[j * n + i]);
      EXPECT_NEAR(d[i * n + j], full[cells[j].y * w + cells[j].x], 1e-4) << i << " -> " << j;
    }
  }
  EXPECT_DOUBLE_EQ(d[0 * n + 5], 0.0);   // the same cell twice
  EXPECT_DOUBLE_EQ(d[0 * n + 1], 1.0);   // neighbours
  EXPECT_EQ(d[0 * n + 4], -1.0);         // inside the closed room
  EXPECT_GT(d[0 * n + 2], 28.0 + 20.0);  // round the wall
}

TEST(PathLengthsBetween, CountsItsCellsPassable) {
  std::vector<uint8_t> g(5 * 1, 1);
  g[4] = 0;  // a goal on a blocked cell at the end of a corridor
  const auto d = pathLengthsBetween(g, 5, 1, {Cell{0, 0}, Cell{4, 0}});
  EXPECT_DOUBLE_EQ(d[1], 4.0);
  EXPECT_THROW(pathLengthsBetween(g, 5, 1, {Cell{5, 0}}), std::invalid_argument);
  EXPECT_TRUE(pathLengthsBetween(g, 5, 1, {}).empty());
}
