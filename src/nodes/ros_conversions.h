// Pure conversions between ROS messages and core types, shared by the roscpp nodes.
#pragma once

#include <string>

#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/LaserScan.h>

#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/occupancy_grid.h"

namespace mbot {
namespace ros_glue {

/// Copies a sensor_msgs/LaserScan into the core's scan type (ranges kept as they are, REP 117).
core::LaserScan fromRos(const sensor_msgs::LaserScan& msg);

/// Fills `out` (data, info) from a grid; the caller sets the header (frame, stamp).
void toRos(const core::OccupancyGrid& grid, nav_msgs::OccupancyGrid& out);

/// Empty when the scan's header and ranges are consistent, else a sentence saying what is wrong
/// (NaN in the beam geometry, range_max <= range_min, no beams), for a warning naming the topic.
std::string describeScanProblem(const sensor_msgs::LaserScan& msg);

}  // namespace ros_glue
}  // namespace mbot
