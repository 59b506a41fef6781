// What the slam_gmapping node (and slam_offline) need from a SLAM backend, so that the node serves
// the same topics and parameters whichever backend runs: the particle filter (rbpf_slam.h) or the
// pose graph (graph_slam.h).
//
// Frames: odometry poses are the robot base in the odom frame; estimates are the base in the map
// frame, which starts where odometry is at the first scan. Units: metres, radians, seconds.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace core {

/// One pose of the estimated trajectory, made when a scan updated the map.
struct TrajectoryNode {
  Eigen::Vector3d pose;       ///< base in map
  Eigen::Vector3d odom;       ///< base in odom at the same time
  double time_s;
  std::shared_ptr<const TrajectoryNode> parent;  ///< the RBPF shares histories; null for the graph
};

class SlamBackend {
 public:
  virtual ~SlamBackend() = default;
  /// Feeds one scan with the odometry pose at its time. Returns true when the scan updated the
  /// map (motion since the last update exceeded linearUpdate/angularUpdate, or the first scan).
  virtual bool processScan(const Eigen::Vector3d& odom_pose, const LaserScan& scan, double time_s) = 0;
  /// The base in the map frame now: the latest estimate composed with odometry since.
  virtual Eigen::Vector3d currentPose() const = 0;
  /// The estimated trajectory, oldest first, one node per update.
  virtual std::vector<TrajectoryNode> trajectory() const = 0;
  /// gmapping's occupancy picture of the map (hits / visits > occ_thresh is occupied).
  virtual OccupancyImage occupancy(double occ_thresh) const = 0;
  /// True when the estimate has moved what occupancy() last drew without a new update (the pose
  /// graph's optimizer, in its own thread, after a loop closure): the map is worth publishing again
  /// even if the robot stands still.
  virtual bool mapOutdated() const { return false; }
  /// True when currentPose() moves against odometry at every scan (scans are tracked), not only
  /// at updates: the node then publishes map -> odom for every scan.
  virtual bool tracksEveryScan() const { return false; }
  /// [m] How weakly the last tracked scan's match fixed the robot's position: the standard
  /// deviation along the direction it constrained least (GraphSlamStats::match_weakest_m); < 0
  /// when scans are not tracked.
  virtual double trackingWeakestSigma() const { return -1.0; }
  virtual int updates() const = 0;
};

}  // namespace core
}  // namespace mbot
