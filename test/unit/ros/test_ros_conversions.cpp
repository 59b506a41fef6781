#include <atomic>
#include <chrono>
#include <limits>
#include <thread>

#include <gtest/gtest.h>

#include "../../../src/nodes/ros_conversions.h"
#include "../../../src/nodes/sim_rate.h"

TEST(RosConversions, ScanKeepsRep117Ranges) {
  sensor_msgs::LaserScan msg;
  msg.angle_min = -1.0f;
  msg.angle_increment = 0.5f;
  msg.range_min = 0.1f;
  msg.range_max = 5.0f;
  msg.ranges = {1.0f, std::numeric_limits<float>::infinity(), 2.0f};
  const auto scan = mbot::ros_glue::fromRos(msg);
  EXPECT_DOUBLE_EQ(scan.beamAngle(2), 0.0);
  EXPECT_TRUE(std::isinf(scan.ranges_m[1]));
  EXPECT_TRUE(mbot::ros_glue::describeScanProblem(msg).empty());
  msg.range_max = 0.0f;
  EXPECT_NE(mbot::ros_glue::describeScanProblem(msg).find("range_max"), std::string::npos);
  msg.ranges.clear();
  EXPECT_NE(mbot::ros_glue::describeScanProblem(msg).find("no beams"), std::string::npos);
}

TEST(RosConversions, SeqGapCounterCountsMissedMessagesOnly) {
  mbot::ros_glue::SeqGapCounter c;
  EXPECT_EQ(c.feed(10), 0u);  // the first message: nothing known before it
  EXPECT_EQ(c.feed(11), 0u);
  EXPECT_EQ(c.feed(15), 3u);  // 12, 13 and 14 were dropped
  EXPECT_EQ(c.feed(16), 0u);
  EXPECT_EQ(c.feed(2), 0u);   // backwards: a restarted publisher, not a loss
  EXPECT_EQ(c.feed(4), 1u);
  EXPECT_EQ(c.total(), 4u);
  mbot::ros_glue::SeqGapCounter unset;  // a publisher that leaves seq at 0
  for (int i = 0; i < 5; ++i) EXPECT_EQ(unset.feed(0), 0u);
  EXPECT_EQ(unset.total(), 0u);
}

TEST(RosConversions, GridInfoAndData) {
  mbot::core::OccupancyGrid grid(4, 3, 0.5, {-1.0, 2.0});
  grid.setLogOdds({1, 2}, 5.0f);
  nav_msgs::OccupancyGrid msg;
  mbot::ros_glue::toRos(grid, msg);
  EXPECT_EQ(msg.info.width, 4u);
  EXPECT_EQ(msg.info.height, 3u);
  EXPECT_FLOAT_EQ(msg.info.resolution, 0.5f);
  EXPECT_DOUBLE_EQ(msg.info.origin.position.x, -1.0);
  EXPECT_DOUBLE_EQ(msg.info.origin.orientation.w, 1.0);
  ASSERT_EQ(msg.data.size(), 12u);
  EXPECT_EQ(msg.data[2 * 4 + 1], 99);
  EXPECT_EQ(msg.data[0], -1);
}

// A clock that goes back while the loop works (reset_simulation during a move_base cycle): the
// next wait is one period of the new clock, not the whole jump back.
TEST(SimRate, AClockThatWentBackDuringTheWorkIsWaitedForOnePeriod) {
  ros::Time::init();  // simulated time, set by hand below
  ros::Time::setNow(ros::Time(500.0));
  mbot::ros_glue::SimRate rate(10.0);  // the first wait ends at 500.1
  ros::Time::setNow(ros::Time(0.5));   // the reset, during the cycle's work
  std::atomic<bool> done{false};
  std::thread clock([&] {  // the simulator's /clock: 0.02 s a millisecond, up to 520 s at most
    for (double t = 0.5; !done && t < 520.0; t += 0.02) {
      ros::Time::setNow(ros::Time(t));
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  rate.sleep();
  const double woke = ros::Time::now().toSec();
  done = true;
  clock.join();
  EXPECT_LT(woke, 1.0) << "the wait went on until the clock came back to where it was before the jump";
  EXPECT_GE(woke, 0.55);
}
