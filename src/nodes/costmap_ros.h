// Costmap2DROS: a LayeredCostmap (core) fed by ROS topics and tf2, published for rviz.
//
// Subscribes the static layer's map topic (nav_msgs/OccupancyGrid, latched or repeated, so it follows
// a growing SLAM map; with subscribe_to_updates also <map_topic>_updates, map_msgs/OccupancyGridUpdate,
// as costmap_2d's StaticLayer) and each LaserScan observation source; looks the robot and the sensors up in
// tf2 in global_frame; publishes ~<name>/costmap (nav_msgs/OccupancyGrid, the whole grid at
// publish_frequency and to each new subscriber), ~<name>/costmap_updates
// (map_msgs/OccupancyGridUpdate, the window that changed since the last publication, as costmap_2d
// sends it) and ~<name>/footprint (geometry_msgs/PolygonStamped). Each filter with a mask_topic
// subscribes it (nav_msgs/OccupancyGrid in global_frame, at the costmap's resolution, as map_server
// serves a mask image); a filter that cannot be used is reported once as an error and left out, and
// the costmap goes on without it. Thread-safe: callbacks come from
// an AsyncSpinner, the planner and controller read the grid under lock().
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>

#include "mbot_slam_navigation/core/layered_costmap.h"
#include "mbot_slam_navigation/core/map_updates.h"

namespace mbot {
namespace ros_glue {

class CostmapROS {
 public:
  /// Reads ~<name>; throws core::ParamError naming the key. `beat` is called with the stamp of
  /// every robot pose used (the simulator's auto pacing).
  CostmapROS(const std::string& name, tf2_ros::Buffer& tf, std::function<void(const ros::Time&)> beat);

  const core::CostmapConfig& config() const { return layered_->config(); }
  /// The robot's (x, y, yaw) in global_frame, or nullopt (reason in tfProblem()).
  std::optional<Eigen::Vector3d> lookupRobotPose();
  std::string tfProblem() const;
  /// One update cycle (also run by the update timer); false when the pose or the map is missing.
  bool update();
  /// (current, why not): stale sensors or a costmap never updated.
  std::pair<bool, std::string> isCurrent();
  void publish();
  void resetLayers(const std::optional<Eigen::Vector3d>& keep = std::nullopt);
  /// shutdown_costmaps: no updates or sensor processing until start().
  void stop() { active_ = false; }
  void start() { active_ = true; }

  /// The keep-out zone at `p` (global_frame), "" when none; see LayeredCostmap::keepoutZoneAt.
  std::string keepoutZoneAt(const Eigen::Vector2d& p) const;
  core::LayeredCostmap::SpeedLimit speedLimitAt(const Eigen::Vector3d& pose) const;

  /// The grid, valid while the lock is held.
  std::unique_lock<std::mutex> lock() { return std::unique_lock<std::mutex>(mutex_); }
  const core::Costmap& master() const { return layered_->master(); }
  /// LayeredCostmap::contactCost, for the map's current resolution (valid while the lock is held).
  uint8_t contactCost() const { return layered_->contactCost(); }
  /// LayeredCostmap::roomyCost, likewise.
  uint8_t roomyCost() const { return layered_->roomyCost(); }

 private:
  void onMap(const nav_msgs::OccupancyGrid::ConstPtr& msg);
  void onMapUpdate(const map_msgs::OccupancyGridUpdate::ConstPtr& msg);
  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg, std::size_t source);
  void onMask(const nav_msgs::OccupancyGrid::ConstPtr& msg, std::size_t filter);
  void reportFilterErrors();
  void publishFootprint(const Eigen::Vector3d& pose);

  std::string name_;
  tf2_ros::Buffer& tf_;
  std::function<void(const ros::Time&)> beat_;
  std::unique_ptr<core::LayeredCostmap> layered_;
  mutable std::mutex mutex_;
  core::MapUpdateLog map_log_;  // the static layer's map updates newer than its whole map (mutex_)
  std::string tf_problem_;
  // Set and read from several callback threads.
  std::atomic<bool> ever_updated_{false}, active_{true}, send_full_{true};
  core::CellWindow unpublished_;
  ros::Publisher costmap_pub_, updates_pub_, footprint_pub_;
  std::vector<ros::Subscriber> subscribers_;
  ros::Subscriber map_updates_sub_;
  ros::Timer update_timer_, publish_timer_;
  ros::WallTimer mask_watch_;
  std::vector<std::atomic<bool>> mask_received_;
};

}  // namespace ros_glue
}  // namespace mbot
