// Pure conversions between ROS messages and core types, shared by the roscpp nodes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nav_msgs/OccupancyGrid.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <sensor_msgs/LaserScan.h>

#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/occupancy_grid.h"
#include "mbot_slam_navigation/core/params.h"
#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace ros_glue {

/// Copies a sensor_msgs/LaserScan into the core's scan type (ranges kept as they are, REP 117).
core::LaserScan fromRos(const sensor_msgs::LaserScan& msg);

/// Fills `out` (data, info) from a grid; the caller sets the header (frame, stamp).
void toRos(const core::OccupancyGrid& grid, nav_msgs::OccupancyGrid& out);
void toRos(core::OccupancyImage&& image, nav_msgs::OccupancyGrid& out);  // takes the image's cells

/// Empty when the scan's header and ranges are consistent, else a sentence saying what is wrong
/// (NaN or inf in the beam geometry, range_max <= range_min, no beams, fewer or more beams than
/// angle_min..angle_max announce, no usable range at all), for a warning naming the topic.
std::string describeScanProblem(const sensor_msgs::LaserScan& msg);

/// Counts the messages a subscriber missed, from their header.seq: roscpp drops the oldest message
/// without a word when a subscriber's queue is full, so a node that falls behind its scans would
/// otherwise not know. seq 0 (publishers that leave it unset, bags written without it) and seq
/// going backwards (a restarted publisher or bag) count nothing.
class SeqGapCounter {
 public:
  /// Feeds one received message's seq; returns how many were missed just before it.
  uint64_t feed(uint32_t seq) {
    uint64_t missed = 0;
    if (seen_ && uint64_t{seq} > uint64_t{last_} + 1) missed = uint64_t{seq} - last_ - 1;  // no wrap at 2^32 - 1
    seen_ = true;
    last_ = seq;
    total_ += missed;
    return missed;
  }
  uint64_t total() const { return total_; }

 private:
  bool seen_ = false;
  uint32_t last_ = 0;
  uint64_t total_ = 0;
};

/// A parameter server value as the core's ParamValue (dates and binary become strings).
core::ParamValue fromXmlRpc(XmlRpc::XmlRpcValue& value);

/// (yaw, warning) of a quaternion for planar navigation, or (nullopt, why) when it cannot be used
/// (ROS's isQuaternionValid): NaN, zero length or tilted; one that is not unit length is normalized
/// and the warning says so. `what` names it in the messages.
std::pair<std::optional<double>, std::string> planarYaw(double x, double y, double z, double w, const std::string& what);

}  // namespace ros_glue
}  // namespace mbot
