// A planar laser scan without ROS types: the fields of sensor_msgs/LaserScan the core needs.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace mbot {
namespace core {

/// Beams are counter-clockwise from angle_min in the sensor frame (REP 103). Ranges follow REP 117:
/// +inf means no return within range_max, -inf an object closer than range_min, NaN an invalid beam.
struct LaserScan {
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  std::vector<float> ranges_m;

  /// Angle of beam i in the sensor frame [rad].
  double beamAngle(std::size_t i) const { return angle_min_rad + static_cast<double>(i) * angle_increment_rad; }
  /// Whether the beams cover the full circle (the last one next to the first).
  bool seesAllRound() const {
    const double step = std::abs(angle_increment_rad);
    return step * static_cast<double>(ranges_m.size()) >= 2.0 * M_PI - 0.5 * step;
  }
  /// [m] the farthest range used of this scan when a user asks for at most `max_range_m`: the
  /// smaller of the two (range_max unset: `max_range_m`).
  double usableRange(double max_range_m) const {
    return std::min(max_range_m, range_max_m > 0.0 ? range_max_m : max_range_m);
  }
};

}  // namespace core
}  // namespace mbot
