#include "ros_conversions.h"

#include <cmath>
#include <sstream>

namespace mbot {
namespace ros_glue {

core::LaserScan fromRos(const sensor_msgs::LaserScan& msg) {
  core::LaserScan scan;
  scan.angle_min_rad = msg.angle_min;
  scan.angle_increment_rad = msg.angle_increment;
  scan.range_min_m = msg.range_min;
  scan.range_max_m = msg.range_max;
  scan.ranges_m = msg.ranges;
  return scan;
}

void toRos(const core::OccupancyGrid& grid, nav_msgs::OccupancyGrid& out) {
  out.info.resolution = static_cast<float>(grid.resolution());
  out.info.width = grid.width();
  out.info.height = grid.height();
  out.info.origin.position.x = grid.origin().x();
  out.info.origin.position.y = grid.origin().y();
  out.info.origin.position.z = 0.0;
  out.info.origin.orientation.w = 1.0;
  const std::vector<int8_t> data = grid.toRosData();
  out.data.assign(data.begin(), data.end());
}

std::string describeScanProblem(const sensor_msgs::LaserScan& msg) {
  std::ostringstream why;
  if (msg.ranges.empty()) {
    why << "it has no beams";
  } else if (!std::isfinite(msg.angle_min) || !std::isfinite(msg.angle_increment) || msg.angle_increment == 0.0f) {
    why << "its angle_min/angle_increment (" << msg.angle_min << ", " << msg.angle_increment << ") are not usable";
  } else if (!std::isfinite(msg.range_max) || !(msg.range_max > msg.range_min)) {
    why << "its range_max (" << msg.range_max << ") is not above range_min (" << msg.range_min << ")";
  }
  return why.str();
}

}  // namespace ros_glue
}  // namespace mbot
