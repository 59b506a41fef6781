#include <random>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/map_updates.h"

using mbot::core::changedWindows;
using mbot::core::GridWindow;
using mbot::core::OccupancyImage;
using mbot::core::paddedToBlocks;

// Applying the windows of `after` to `before` gives `after`; together they hold fewer cells than
// the whole grid when little changed.
TEST(MapUpdates, WindowsOfABandOfNewCellsRebuildTheMapAndHoldLittleMore) {
  const int w = 400, h = 300;
  std::vector<int8_t> before(w * h, -1), after;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < 150; ++c) before[r * w + c] = (r * 7 + c) % 13 == 0 ? 100 : 0;
  after = before;
  // A robot's laser reach advanced by 0.6 m (12 cells): a ring band 108-120 cells from (150, 150).
  int changed = 0;
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const double d = std::hypot(c - 150.0, r - 150.0);
      if (d >= 108.0 && d < 120.0 && after[r * w + c] != 0) {
        after[r * w + c] = 0;
        ++changed;
      }
    }
  }
  std::mt19937 rng(3);  // and a few cells anywhere
  for (int k = 0; k < 20; ++k) {
    const int i = static_cast<int>(rng() % (w * h));
    changed += after[i] != 100;
    after[i] = 100;
  }
  const auto windows = changedWindows(before, after, w, h, 16);
  std::vector<int8_t> rebuilt = before;
  long sent = 0;
  for (const GridWindow& win : windows) {
    ASSERT_GE(win.x, 0);
    ASSERT_GE(win.y, 0);
    ASSERT_LE(win.x + win.width, w);
    ASSERT_LE(win.y + win.height, h);
    for (int r = win.y; r < win.y + win.height; ++r)
      for (int c = win.x; c < win.x + win.width; ++c) rebuilt[r * w + c] = after[r * w + c];
    sent += static_cast<long>(win.width) * win.height;
  }
  EXPECT_EQ(rebuilt, after);
  // One window around the band (its bounding box) would hold 20 times the changed cells; the
  // tiles hold about 2.5 times (the band's diagonal stretches fill their tiles' boxes).
  EXPECT_LT(sent, 3 * changed) << windows.size() << " windows, " << sent << " cells for " << changed << " changed";
  EXPECT_LT(sent + 64 * static_cast<long>(windows.size()), w * h / 6);
  EXPECT_TRUE(changedWindows(after, after, w, h, 16).empty());
  EXPECT_THROW(changedWindows(before, after, w, h + 1, 16), std::invalid_argument);
}

TEST(MapUpdates, PaddedToBlocksKeepsTheCellsWhereTheyAreAndItsSizeWhileTheyStayInABlock) {
  OccupancyImage m;
  m.width = 7;
  m.height = 5;
  m.resolution = 0.05;
  m.origin = {-0.35, 0.10};  // cells -7..-1 and 2..6 of the frame
  m.data.assign(35, 0);
  m.data[2 * 7 + 3] = 100;  // cell (3, 2): frame cell (-4, 4)
  const auto p = paddedToBlocks(m, 8);
  EXPECT_EQ(p.width, 8);   // frame cells -8..-1
  EXPECT_EQ(p.height, 8);  // frame cells 0..7
  EXPECT_NEAR(p.origin.x(), -0.40, 1e-9);
  EXPECT_NEAR(p.origin.y(), 0.0, 1e-9);
  const int col = static_cast<int>(std::lround((-0.35 + 3.5 * 0.05 - p.origin.x()) / 0.05 - 0.5));
  const int row = static_cast<int>(std::lround((0.10 + 2.5 * 0.05 - p.origin.y()) / 0.05 - 0.5));
  EXPECT_EQ(p.data[row * p.width + col], 100);
  int unknown = 0;
  for (int8_t v : p.data) unknown += v == -1;
  EXPECT_EQ(unknown, 64 - 35);
  // The map grows by one cell within the same block: the padded size and origin stay.
  OccupancyImage grown = m;
  grown.width = 8;
  grown.data.assign(40, 0);
  grown.origin.x() = -0.40;
  const auto q = paddedToBlocks(grown, 8);
  EXPECT_EQ(q.width, p.width);
  EXPECT_EQ(q.height, p.height);
  EXPECT_NEAR(q.origin.x(), p.origin.x(), 1e-9);
  EXPECT_THROW(paddedToBlocks(m, 0), std::invalid_argument);
  // A map whose edge went back across a block's edge (frame cells -9..-1 and back to -7..-1):
  // covering what was sent, it keeps its size; without, it would shrink and be sent whole again.
  OccupancyImage wider = m;
  wider.width = 9;
  wider.origin.x() = -0.45;
  wider.data.assign(45, 0);
  const auto sent = mbot::core::frameCells(paddedToBlocks(wider, 8));
  EXPECT_EQ(sent.x, -16);
  EXPECT_EQ(sent.width, 16);
  const auto kept = paddedToBlocks(m, 8, &sent);
  EXPECT_EQ(mbot::core::frameCells(kept).x, sent.x);
  EXPECT_EQ(kept.width, sent.width);
  EXPECT_EQ(kept.height, sent.height);
  EXPECT_EQ(paddedToBlocks(m, 8).width, 8);
}
