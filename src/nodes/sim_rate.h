// SimRate: a fixed-rate loop for the nodes (move_base, slam_gmapping) that does not poll /clock.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include <ros/ros.h>

namespace mbot {
namespace ros_glue {

// A fixed-rate loop like ros::Rate, but under simulated time it does not poll: roscpp's sleep
// wakes every millisecond of wall time until /clock passes the deadline (about 14 wake-ups per
// 10 Hz cycle at 7x real time, each a context switch). This one sleeps for the wall time the
// remaining simulated time should take at the pace /clock has been advancing, then checks again.
// A clock that jumps back (a reset simulation) ends the wait, as ros::Rate does; one that jumped
// back before the wait (during the loop's work) gets a wait of one period, as ros::Rate gives.
// The loop ends when ros::shutdown() is called (not only when it is done, as ros::ok() says).
class SimRate {
 public:
  explicit SimRate(double hz) : period_(1.0 / hz), next_(ros::Time::now() + period_) {}
  void sleep() {
    if (next_ > ros::Time::now() + period_ * 2.0) {
      // The clock went back since the last wait. Waiting for next_ would wait out the whole jump:
      // after a reset_simulation at 500 s, move_base's goal loop would stand still for 50 s of
      // wall time at ten times real time, its goal neither aborted nor followed.
      next_ = ros::Time::now() + period_;
    }
    if (!ros::Time::isSimTime()) {
      const ros::Duration left = next_ - ros::Time::now();
      if (left > ros::Duration(0)) left.sleep();
    } else {
      ros::Time last = ros::Time::now();
      ros::WallTime wall_last = ros::WallTime::now();
      while (!ros::isShuttingDown() && last < next_) {
        const double wall = std::clamp((next_ - last).toSec() / pace_.load(), 0.0005, 0.05);
        std::this_thread::sleep_for(std::chrono::duration<double>(wall));
        const ros::Time now = ros::Time::now();
        const ros::WallTime wall_now = ros::WallTime::now();
        if (now < last) break;  // the clock went back
        const double dw = (wall_now - wall_last).toSec();
        if (dw > 0.005 && now > last) pace_ = std::clamp((now - last).toSec() / dw, 0.05, 500.0);
        last = now;
        wall_last = wall_now;
      }
    }
    const ros::Time now = ros::Time::now();
    next_ += period_;
    if (next_ < now || next_ > now + period_ * 2.0) next_ = now + period_;  // behind, or the clock jumped
  }

 private:
  ros::Duration period_;
  ros::Time next_;
  // Simulated seconds per wall second, as last seen (one clock for all loops). Starting high
  // only costs a few short first waits; starting low would oversleep.
  static inline std::atomic<double> pace_{20.0};
};

}  // namespace ros_glue
}  // namespace mbot
