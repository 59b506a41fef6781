// known_pose_mapper: occupancy mapping with known poses. Integrates every LaserScan on `scan` into a
// log-odds grid at the pose tf gives for the scan's frame in `~map_frame`, and publishes the grid on
// `map` / `map_metadata` (latched) every `~map_update_interval` seconds. Use it when the poses are
// right already (a simulator's ground truth, a localized robot); slam_gmapping estimates them.
#include <cmath>
#include <memory>

#include <nav_msgs/MapMetaData.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>
#include <tf2_ros/transform_listener.h>

#include "mbot_slam_navigation/core/occupancy_grid.h"
#include "ros_conversions.h"

namespace {

struct Options {
  std::string map_frame = "map";   // frame the grid is built in
  double delta = 0.05;             // [m] cell size
  double xmin = -10.0, ymin = -10.0, xmax = 10.0, ymax = 10.0;  // [m] initial extent; grows as needed
  double max_urange = -1.0;        // [m] usable range; <= 0 means the scan's range_max
  double map_update_interval = 1.0;  // [s]
};

class KnownPoseMapper {
 public:
  KnownPoseMapper() : pnh_("~"), tf_listener_(tf_buffer_) {
    pnh_.param("map_frame", opt_.map_frame, opt_.map_frame);
    pnh_.param("delta", opt_.delta, opt_.delta);
    pnh_.param("xmin", opt_.xmin, opt_.xmin);
    pnh_.param("ymin", opt_.ymin, opt_.ymin);
    pnh_.param("xmax", opt_.xmax, opt_.xmax);
    pnh_.param("ymax", opt_.ymax, opt_.ymax);
    pnh_.param("maxUrange", opt_.max_urange, opt_.max_urange);
    pnh_.param("map_update_interval", opt_.map_update_interval, opt_.map_update_interval);
    if (!(opt_.delta > 0.0) || !(opt_.xmax > opt_.xmin) || !(opt_.ymax > opt_.ymin)) {
      ROS_FATAL("known_pose_mapper: ~delta must be > 0 and ~xmax > ~xmin, ~ymax > ~ymin (got delta=%g, x %g..%g, y %g..%g)",
                opt_.delta, opt_.xmin, opt_.xmax, opt_.ymin, opt_.ymax);
      ros::shutdown();
      return;
    }
    grid_ = std::make_unique<mbot::core::OccupancyGrid>(
        static_cast<int>(std::ceil((opt_.xmax - opt_.xmin) / opt_.delta)),
        static_cast<int>(std::ceil((opt_.ymax - opt_.ymin) / opt_.delta)), opt_.delta,
        Eigen::Vector2d(opt_.xmin, opt_.ymin));
    map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
    meta_pub_ = nh_.advertise<nav_msgs::MapMetaData>("map_metadata", 1, true);
    scan_sub_ = nh_.subscribe("scan", 5, &KnownPoseMapper::onScan, this);
    timer_ = nh_.createTimer(ros::Duration(opt_.map_update_interval), &KnownPoseMapper::publish, this);
  }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    const std::string problem = mbot::ros_glue::describeScanProblem(*msg);
    if (!problem.empty()) {
      ROS_WARN_THROTTLE(5.0, "known_pose_mapper: skipping scan on %s (frame '%s'): %s",
                        scan_sub_.getTopic().c_str(), msg->header.frame_id.c_str(), problem.c_str());
      return;
    }
    geometry_msgs::TransformStamped tf;
    try {
      tf = tf_buffer_.lookupTransform(opt_.map_frame, msg->header.frame_id, msg->header.stamp, ros::Duration(0.2));
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5.0, "known_pose_mapper: no transform from '%s' to '%s' for a scan on %s: %s",
                        msg->header.frame_id.c_str(), opt_.map_frame.c_str(), scan_sub_.getTopic().c_str(), e.what());
      return;
    }
    const Eigen::Vector3d pose(tf.transform.translation.x, tf.transform.translation.y,
                               tf2::getYaw(tf.transform.rotation));
    const double usable = opt_.max_urange > 0.0 ? opt_.max_urange : msg->range_max;
    grid_->growToInclude(pose.head<2>(), usable + opt_.delta);
    grid_->integrateScan(pose, mbot::ros_glue::fromRos(*msg), usable);
    ++scans_;
  }

  void publish(const ros::TimerEvent&) {
    if (scans_ == 0) return;
    nav_msgs::OccupancyGrid map;
    mbot::ros_glue::toRos(*grid_, map);
    map.header.frame_id = opt_.map_frame;
    map.header.stamp = ros::Time::now();
    map.info.map_load_time = map.header.stamp;
    map_pub_.publish(map);
    meta_pub_.publish(map.info);
    ROS_DEBUG("known_pose_mapper: %d scans integrated, %d cells known", scans_, grid_->observedCount());
  }

  ros::NodeHandle nh_, pnh_;
  Options opt_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  std::unique_ptr<mbot::core::OccupancyGrid> grid_;
  ros::Publisher map_pub_, meta_pub_;
  ros::Subscriber scan_sub_;
  ros::Timer timer_;
  int scans_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "known_pose_mapper");
  KnownPoseMapper mapper;
  ros::spin();
  return 0;
}
