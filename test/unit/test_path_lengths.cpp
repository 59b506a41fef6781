#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "mbot_slam_navigation/core/path_lengths.h"

using mbot::core::Cell;
using mbot::core::pathLengths;

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
