#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/bresenham.h"

using mbot::core::bresenhamLine;
using mbot::core::Cell;
using mbot::core::walkLine;
using mbot::core::walkSegment;

TEST(WalkSegment, EveryCellTheSegmentCrossesInOrder) {
  // From (43.4, 52.2) to (42.2, 53.26) in cell units the segment crosses x = 43 at y = 52.55 and
  // y = 53 at x = 42.49: cells (43, 52), (42, 52), (42, 53). Bresenham between the end cells steps
  // diagonally from (43, 52) to (42, 53).
  std::vector<Cell> cells;
  walkSegment(43.4, 52.2, 42.2, 53.26, [&](const Cell& c) {
    cells.push_back(c);
    return true;
  });
  ASSERT_EQ(cells.size(), 3u);
  EXPECT_EQ(cells[0], (Cell{43, 52}));
  EXPECT_EQ(cells[1], (Cell{42, 52}));
  EXPECT_EQ(cells[2], (Cell{42, 53}));
  EXPECT_EQ(bresenhamLine({43, 52}, {42, 53}).size(), 2u);
  // Exactly through a corner: both cells beside it, then the diagonal one.
  cells.clear();
  walkSegment(0.5, 0.5, 1.5, 1.5, [&](const Cell& c) {
    cells.push_back(c);
    return true;
  });
  EXPECT_EQ(cells.size(), 4u);
  EXPECT_EQ(cells.back(), (Cell{1, 1}));
  // Long segments in every direction: 4-connected steps, from the first cell to the last.
  for (int k = 0; k < 32; ++k) {
    const double a = k * M_PI / 16 + 0.1;
    const double x0 = 10.3, y0 = 10.7, x1 = x0 + 7.9 * std::cos(a), y1 = y0 + 7.9 * std::sin(a);
    cells.clear();
    walkSegment(x0, y0, x1, y1, [&](const Cell& c) {
      cells.push_back(c);
      return true;
    });
    EXPECT_EQ(cells.front(), (Cell{10, 10}));
    EXPECT_EQ(cells.back(), (Cell{static_cast<int>(std::floor(x1)), static_cast<int>(std::floor(y1))}));
    for (std::size_t i = 1; i < cells.size(); ++i) {
      EXPECT_EQ(std::abs(cells[i].x - cells[i - 1].x) + std::abs(cells[i].y - cells[i - 1].y), 1) << k << " " << i;
    }
  }
}

TEST(Bresenham, IncludesBothEndsInOrder) {
  const auto line = bresenhamLine({2, 3}, {9, 5});
  ASSERT_FALSE(line.empty());
  EXPECT_EQ(line.front(), (Cell{2, 3}));
  EXPECT_EQ(line.back(), (Cell{9, 5}));
  EXPECT_EQ(line.size(), 8u);  // one cell per column along the major axis
}

TEST(Bresenham, StepsAreEightConnectedInEveryOctant) {
  const Cell from{0, 0};
  for (const Cell to : {Cell{7, 3}, Cell{3, 7}, Cell{-3, 7}, Cell{-7, 3}, Cell{-7, -3}, Cell{-3, -7}, Cell{3, -7},
                        Cell{7, -3}}) {
    const auto line = bresenhamLine(from, to);
    EXPECT_EQ(line.back(), to);
    EXPECT_EQ(line.size(), 8u);
    for (std::size_t i = 1; i < line.size(); ++i) {
      EXPECT_LE(std::abs(line[i].x - line[i - 1].x), 1);
      EXPECT_LE(std::abs(line[i].y - line[i - 1].y), 1);
    }
  }
}

TEST(Bresenham, DegenerateAndAxisAlignedLines) {
  EXPECT_EQ(bresenhamLine({4, 4}, {4, 4}).size(), 1u);
  const auto vertical = bresenhamLine({1, 5}, {1, -2});
  ASSERT_EQ(vertical.size(), 8u);
  for (const Cell& c : vertical) EXPECT_EQ(c.x, 1);
  const auto diagonal = bresenhamLine({0, 0}, {-4, -4});
  for (std::size_t i = 0; i < diagonal.size(); ++i) EXPECT_EQ(diagonal[i], (Cell{-int(i), -int(i)}));
}

TEST(Bresenham, VisitorCanStopEarly) {
  int visited = 0;
  const bool reached = walkLine({0, 0}, {10, 0}, [&](Cell c) {
    ++visited;
    return c.x < 4;
  });
  EXPECT_FALSE(reached);
  EXPECT_EQ(visited, 5);
}
