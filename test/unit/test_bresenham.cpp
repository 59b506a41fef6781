#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/bresenham.h"

using mbot::core::bresenhamLine;
using mbot::core::Cell;
using mbot::core::walkLine;

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
