// slam_gmapping's parameters (the node's private namespace), ROS-free: gmapping's names and
// defaults, the pose graph's own, the node's; read and checked once here for the node
// (slam_gmapping_node.cpp), the offline runner (slam/backends.py) and the reference page.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/params.h"
#include "mbot_slam_navigation/core/rbpf_slam.h"

namespace mbot {
namespace core {

struct SlamConfig {
  std::string base_frame = "base_link", odom_frame = "odom", map_frame = "map";
  double map_update_interval = 5.0;        ///< [s] between map publications
  /// Publish what changed on map_updates (map_msgs/OccupancyGridUpdate) and the whole map only when
  /// its size grows (by 4 m blocks), a subscriber comes, or every whole_map_period: for subscribers
  /// on other hosts (map_merge's robot_map_updates_topic).
  bool publish_updates = false;
  double whole_map_period = 60.0;          ///< [s] with publish_updates, the whole map at least this often
  double transform_publish_period = 0.05;  ///< [s] between map -> odom broadcasts; 0: none
  double occ_thresh = 0.25;                ///< occupancy above which a cell is published occupied
  double tf_delay = -1.0;                  ///< [s] gmapping's; < 0: transform_publish_period
  int throttle_scans = 1;                  ///< process one scan in this many
  int scan_queue_size = 100;               ///< scans held while the node is busy (gmapping: 5)
  double correction_threshold = 0.1;       ///< [m] a correction this large is published on ~correction
  std::string backend = "graph";           ///< graph or rbpf
  // Sessions (graph backend; slam_toolbox's names): a saved graph to start from, where the robot
  // is on it, whether the graph grows, and a file written at shutdown. Paths without extension.
  std::string session_file;                ///< start from <session_file>.posegraph ('' : a new map)
  std::optional<Eigen::Vector3d> map_start_pose;  ///< [m, m, rad] the robot's base in the session's map
  bool map_start_at_dock = false;          ///< the robot stands where the session began
  std::string mode = "mapping";            ///< mapping or localization (on a session)
  std::string save_session_on_exit;        ///< written to <this>.posegraph when the node shuts down
  /// The particle filter's parameters with the matcher, update thresholds and map extent both
  /// backends share; the matcher's laser pose and, when <= 0, max ranges are the caller's to set.
  RbpfParams rbpf;
  /// The pose graph's (and the rbpf's scan-odometry track's) own parameters; the shared ones come
  /// from `rbpf` through RbpfParams::shareWith when the backend is made.
  GraphSlamParams graph;
};

/// Reads slam_gmapping's namespace `ns` (its values given). `default_max_range` [m] is the default
/// of maxUrange and maxRange (the node: -1, the scan's range_max). Unknown keys are warned about
/// with the nearest known one and returned in `unknown` when given. Throws ParamError naming the key.
SlamConfig readSlamConfig(const ParamValue& values, const std::string& ns, const Warn& warn, double default_max_range,
                          std::vector<std::string>* unknown = nullptr);

}  // namespace core
}  // namespace mbot
