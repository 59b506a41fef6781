#include <algorithm>
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

namespace {
// A subscriber's copy of a map: whole maps replace it, updates that fit are written into it.
struct HeldMap {
  int width = 0, height = 0;
  std::vector<int8_t> data;
  void apply(const mbot::core::MapUpdate& u) {
    const GridWindow& w = u.window;
    if (w.x < 0 || w.y < 0 || w.x + w.width > width || w.y + w.height > height) return;
    for (int r = 0; r < w.height; ++r)
      std::copy_n(u.data.begin() + static_cast<long>(r) * w.width, w.width, data.begin() + (w.y + r) * width + w.x);
  }
};
}  // namespace

// A publisher's map grows and changes; whole maps and updates travel on two connections, each in
// order, but interleaved at random. With the log the subscriber ends with the publisher's map
// whatever the interleaving; applying each message as it comes loses updates.
TEST(MapUpdateLog, EveryInterleavingOfWholeMapsAndUpdatesEndsWithThePublishersMap) {
  using mbot::core::MapUpdate;
  using mbot::core::MapUpdateLog;
  struct Whole {
    int64_t stamp;
    HeldMap map;
  };
  int naive_wrong = 0;
  for (int seed = 0; seed < 200; ++seed) {
    std::mt19937 rng(seed);
    std::vector<Whole> wholes;
    std::vector<MapUpdate> updates;
    HeldMap pub{32, 32, std::vector<int8_t>(32 * 32, -1)};
    for (int k = 0; k < 40; ++k) {
      const HeldMap before = pub;
      if (k % 9 == 4) {  // grown by a block to the right and up: the old cells stay where they were
        HeldMap grown{pub.width + 16, pub.height + 16, std::vector<int8_t>((pub.width + 16) * (pub.height + 16), -1)};
        for (int r = 0; r < pub.height; ++r)
          std::copy_n(pub.data.begin() + r * pub.width, pub.width, grown.data.begin() + r * grown.width);
        pub = grown;
      }
      for (int i = 0; i < 30; ++i) pub.data[rng() % pub.data.size()] = static_cast<int8_t>(rng() % 2 ? 0 : 100);
      const int64_t stamp = 1000 + k;
      if (k == 0 || before.width != pub.width || k % 7 == 0) {
        wholes.push_back({stamp, pub});
      } else {
        for (const auto& w : changedWindows(before.data, pub.data, pub.width, pub.height, 16)) {
          MapUpdate u{stamp, w, {}};
          for (int r = w.y; r < w.y + w.height; ++r)
            u.data.insert(u.data.end(), pub.data.begin() + r * pub.width + w.x, pub.data.begin() + r * pub.width + w.x + w.width);
          updates.push_back(u);
        }
      }
    }
    MapUpdateLog log;
    HeldMap sub, naive;
    std::size_t wi = 0, ui = 0;
    while (wi < wholes.size() || ui < updates.size()) {
      const bool take_whole = ui == updates.size() || (wi < wholes.size() && rng() % 4 == 0);
      if (take_whole) {
        sub = naive = wholes[wi].map;
        for (const auto& u : *log.whole(wholes[wi].stamp, wholes[wi].stamp)) sub.apply(u);
        ++wi;
      } else {
        if (log.update(updates[ui])) sub.apply(updates[ui]);
        naive.apply(updates[ui]);
        ++ui;
      }
    }
    ASSERT_EQ(sub.width, pub.width) << "seed " << seed;
    ASSERT_EQ(sub.data, pub.data) << "seed " << seed;
    EXPECT_LT(log.held(), updates.size());
    naive_wrong += naive.data != pub.data;
  }
  EXPECT_GT(naive_wrong, 100);  // the hazard the log is for is real in this test
}

// A whole map older than the one held is stale while the clock is past the one held (a latched
// map sent after a newer one), and starts a new log when the clock went back; updates not newer
// than the whole map held are not applied again.
TEST(MapUpdateLog, AnOlderWholeMapIsStaleUnlessTheClockWentBack) {
  mbot::core::MapUpdateLog log;
  mbot::core::MapUpdate u{5, GridWindow{0, 0, 1, 1}, {100}};
  EXPECT_FALSE(log.update(u));  // no whole map yet: kept
  EXPECT_EQ(log.whole(3, 3)->size(), 1u);
  u.stamp_ns = 3;
  EXPECT_FALSE(log.update(u));  // the whole map has it
  u.stamp_ns = 9;
  EXPECT_TRUE(log.update(u));
  EXPECT_FALSE(log.whole(1, 10).has_value());  // stale: the map held and its update stand
  EXPECT_EQ(log.held(), 2u);
  EXPECT_TRUE(log.whole(2, 2)->empty());  // reset: what came before it is forgotten
  EXPECT_EQ(log.held(), 0u);
}

// Updates without a stamp are applied and not kept; a whole map without one is always taken; the
// log keeps at most its bytes, the oldest updates dropped first.
TEST(MapUpdateLog, UnstampedMessagesAreAppliedAndTheLogIsBounded) {
  mbot::core::MapUpdateLog log(100, 1000);
  EXPECT_TRUE(log.whole(50, 50).has_value());
  EXPECT_TRUE(log.update({0, GridWindow{0, 0, 1, 1}, {100}}));
  EXPECT_EQ(log.held(), 0u);
  EXPECT_TRUE(log.whole(0, 60).has_value());  // unstamped: taken though older than the one held
  for (int k = 1; k <= 30; ++k) log.update({k, GridWindow{0, 0, 10, 10}, std::vector<int8_t>(100, 0)});
  EXPECT_EQ(log.held(), 10u);  // 1000 bytes: the 10 newest
  EXPECT_EQ(log.whole(25, 30)->size(), 5u);
}
