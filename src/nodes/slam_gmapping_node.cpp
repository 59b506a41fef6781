// slam_gmapping: the gmapping node's interface on this package's C++ SLAM backends: `~backend`
// graph (default; core/graph_slam.h, pose graph with loop closure) or rbpf (core/rbpf_slam.h,
// gmapping's particle filter; with `~scan_odometry` true, the default, it moves with the graph's
// scan-matched track instead of the wheels' odometry, and the graph's `local_*` values set the
// track).
//
// Subscribes `scan` (with tf from its frame to ~base_frame and from ~base_frame to ~odom_frame);
// publishes `map`, `map_metadata` (latched) every ~map_update_interval (with ~publish_updates, the
// whole map only when it grows, a subscriber comes or ~whole_map_period passes, and what changed in
// between on `map_updates`, map_msgs/OccupancyGridUpdate), `~entropy` (rbpf only: the
// graph has no particle cloud), `~match_weakest_sigma` (std_msgs/Float64 [m], every tracked scan
// while someone listens: the standard deviation of the scan's match along the direction it
// constrains least; about 1 cm in a room, 5 cm or more along a plain corridor, where odometry gives
// the position); serves `dynamic_map`; broadcasts ~map_frame -> ~odom_frame every
// ~transform_publish_period (stamped ahead, as gmapping) and again after each scan that moved it,
// stamped with that scan; publishes `~correction` (geometry_msgs/TransformStamped: how the map
// frame moved) when a correction moves the robot by more than ~correction_threshold [m] (0.1).
// Holds up to ~scan_queue_size scans (100; gmapping's 5) while it is busy, so that a bag played
// faster than real time is processed whole when the node keeps up on average; scans dropped from
// a full queue, and scans processed more than 5 s after their stamp, are reported in warnings.
// Parameters have gmapping's names and defaults, plus the graph's own
// (graph_slam.h); an unknown private parameter gets a warning naming the nearest known one (the
// tutorial's `base_link` means `base_frame`).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <boost/make_shared.hpp>

#include <malloc.h>
#include <pthread.h>
#include <unistd.h>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/GetMap.h>
#include <nav_msgs/MapMetaData.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Float64.h>
#include <std_msgs/Header.h>
#include <tf2/utils.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/map_updates.h"
#include "mbot_slam_navigation/core/pose2d.h"
#include "mbot_slam_navigation/core/rbpf_slam.h"
#include "mbot_slam_navigation/core/slam_config.h"
#include "mbot_slam_navigation/DeserializePoseGraph.h"
#include "mbot_slam_navigation/SerializePoseGraph.h"
#include "ros_conversions.h"
#include "sim_rate.h"

namespace {

using mbot::core::composePose;
using mbot::core::inversePose;
using mbot::core::relativePose;

Eigen::Vector3d toPose(const geometry_msgs::TransformStamped& t) {
  return {t.transform.translation.x, t.transform.translation.y, tf2::getYaw(t.transform.rotation)};
}

class SlamGmappingNode {
 public:
  SlamGmappingNode() : pnh_("~"), tf_listener_(tf_buffer_) {
    try {
      readParameters();
    } catch (const mbot::core::ParamError& e) {
      // Logged here: once this node's handles are gone, roscpp has shut rosconsole down.
      ROS_FATAL("slam_gmapping: %s", e.what());
      throw;
    }
    if (publish_updates_) {
      // A new subscriber gets the latched whole map, older than the updates sent since, and then
      // (it alone) the newest map whole, which later updates apply to.
      map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>(
          "map", 1,
          [this](const ros::SingleSubscriberPublisher& one) {
            std::lock_guard<std::mutex> lock(map_mutex_);
            if (last_map_) one.publish(*last_map_);
          },
          ros::SubscriberStatusCallback(), ros::VoidConstPtr(), true);
      updates_pub_ = nh_.advertise<map_msgs::OccupancyGridUpdate>("map_updates", 100);
    } else {
      map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
    }
    meta_pub_ = nh_.advertise<nav_msgs::MapMetaData>("map_metadata", 1, true);
    entropy_pub_ = pnh_.advertise<std_msgs::Float64>("entropy", 1, true);
    weakest_pub_ = pnh_.advertise<std_msgs::Float64>("match_weakest_sigma", 10);
    correction_pub_ = pnh_.advertise<geometry_msgs::TransformStamped>("correction", 10);
    if (ros::Time::isSimTime()) heartbeat_pub_ = nh_.advertise<std_msgs::Header>("/sim_heartbeat", 10);
    map_srv_ = nh_.advertiseService("dynamic_map", &SlamGmappingNode::onDynamicMap, this);
    serialize_srv_ = pnh_.advertiseService("serialize_map", &SlamGmappingNode::onSerialize, this);
    deserialize_srv_ = pnh_.advertiseService("deserialize_map", &SlamGmappingNode::onDeserialize, this);
    const std::string session_path = mbot::core::sessionPath(session_file_);
    if (!session_file_.empty() && session_path == mbot::core::sessionPath(save_session_on_exit_) &&
        access(session_path.c_str(), F_OK) != 0 && mode_ == "mapping") {
      // One map kept growing from run to run: the first run has none to continue.
      ROS_INFO("slam_gmapping: no session at %s yet: starting a new map (saved there on shutdown)", session_path.c_str());
    } else if (!session_file_.empty()) {
      std::optional<Eigen::Vector3d> start = map_start_pose_;
      std::string how = "near the given ~map_start_pose";
      if (!start && map_start_at_dock_) how = "where it began (~map_start_at_dock)";
      if (!start && !map_start_at_dock_) how = "by matching the scans against the whole map";
      loadSession(session_file_, start, map_start_at_dock_, mode_ == "localization", how);
    }
    scan_sub_ = nh_.subscribe("scan", scan_queue_size_, &SlamGmappingNode::onScan, this);
    // rviz's 2D Pose Estimate, as amcl and slam_toolbox's localization take it: where the robot is on
    // a loaded session's map (searched around it as ~map_start_pose is).
    initial_pose_sub_ = nh_.subscribe("initialpose", 1, &SlamGmappingNode::onInitialPose, this);
    if (transform_publish_period_ > 0.0) {
      tf_thread_ = std::thread([this] { publishTransformLoop(); });
      pthread_setname_np(tf_thread_.native_handle(), "slam_tf");  // for top -H and /proc
    }
  }

  ~SlamGmappingNode() {
    if (tf_thread_.joinable()) tf_thread_.join();
  }

  /// ~save_session_on_exit: called after ros::spin() returns.
  void saveOnExit() {
    if (save_session_on_exit_.empty()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    auto* graph = dynamic_cast<mbot::core::GraphSlam*>(slam_.get());
    const std::string path = mbot::core::sessionPath(save_session_on_exit_);
    if (!graph || graph->updates() == 0) {
      ROS_WARN("slam_gmapping: nothing mapped; no session written to %s (~save_session_on_exit)", path.c_str());
      return;
    }
    try {
      const std::size_t bytes = mbot::core::saveSessionFile(*graph, path);
      ROS_INFO("slam_gmapping: session saved to %s (%d nodes, %.1f MB; ~save_session_on_exit)", path.c_str(),
               graph->updates(), bytes / 1e6);
    } catch (const std::exception& e) {
      ROS_ERROR("slam_gmapping: the session was not saved (~save_session_on_exit): %s", e.what());
    }
  }

 private:
  void readParameters() {
    XmlRpc::XmlRpcValue values;
    if (!pnh_.getParam("", values)) values = XmlRpc::XmlRpcValue();
    const auto c = mbot::core::readSlamConfig(mbot::ros_glue::fromXmlRpc(values), pnh_.getNamespace(),
                                              [](const std::string& text) { ROS_WARN("slam_gmapping: %s", text.c_str()); },
                                              -1.0);
    base_frame_ = c.base_frame;
    odom_frame_ = c.odom_frame;
    map_frame_ = c.map_frame;
    map_update_interval_ = c.map_update_interval;
    publish_updates_ = c.publish_updates;
    whole_map_period_ = c.whole_map_period;
    transform_publish_period_ = c.transform_publish_period;
    occ_thresh_ = c.occ_thresh;
    throttle_scans_ = c.throttle_scans;
    tf_delay_ = c.tf_delay;
    correction_threshold_ = c.correction_threshold;
    scan_queue_size_ = c.scan_queue_size;
    backend_ = c.backend;
    session_file_ = c.session_file;
    map_start_pose_ = c.map_start_pose;
    map_start_at_dock_ = c.map_start_at_dock;
    mode_ = c.mode;
    save_session_on_exit_ = c.save_session_on_exit;
    params_ = c.rbpf;
    graph_params_ = c.graph;
    graph_params_.keep_scan_poses = false;  // offline scoring only; 40 bytes a scan for as long as the node runs
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    if (scan_gaps_.feed(msg->header.seq) > 0) {
      // The queue (~scan_queue_size) overflowed: the node processes scans slower than they come,
      // and the pose between updates is tracked over the gap.
      ROS_WARN_THROTTLE(10.0, "slam_gmapping: %lu scans on %s dropped from the queue of %d so far (by header.seq): "
                        "the node processes scans slower than they arrive (a rosbag played too fast, a busy machine; "
                        "~throttle_scans, or for the rbpf fewer ~particles, lightens the load)",
                        static_cast<unsigned long>(scan_gaps_.total()), scan_sub_.getTopic().c_str(),
                        scan_queue_size_);
    }
    if (++scan_count_ % std::max(1, throttle_scans_) != 0) return;
    const double lag = (ros::Time::now() - msg->header.stamp).toSec();
    if (lag > kMaxScanTransformAge) {
      // A deep queue (~scan_queue_size) hides a node that falls behind until it overflows; say so
      // before that, when map -> odom for the scan is already too old to be sent.
      ROS_WARN_THROTTLE(10.0, "slam_gmapping: a scan on %s processed %.1f s after its stamp: the node is behind its "
                        "scans (up to ~scan_queue_size %d wait), or the clock is not the scans' (a bag needs "
                        "use_sim_time and rosbag play --clock); map -> odom is sent for scans up to %.0f s old",
                        scan_sub_.getTopic().c_str(), lag, scan_queue_size_, kMaxScanTransformAge);
    }
    const std::string problem = mbot::ros_glue::describeScanProblem(*msg);
    if (!problem.empty()) {
      ROS_WARN_THROTTLE(5.0, "slam_gmapping: skipping a scan on %s (frame '%s'): %s", scan_sub_.getTopic().c_str(),
                        msg->header.frame_id.c_str(), problem.c_str());
      return;
    }
    if (!last_stamp_.isZero() && msg->header.stamp + ros::Duration(1.0) < last_stamp_) {
      ROS_WARN("slam_gmapping: time went backwards (scan at %.3f after %.3f; the simulation reset or a bag restarted?): "
               "starting a new map",
               msg->header.stamp.toSec(), last_stamp_.toSec());
      std::lock_guard<std::mutex> lock(mutex_);
      slam_.reset();
      tf_buffer_.clear();
      map_to_odom_.setZero();
      std::lock_guard<std::mutex> stamps(stamp_mutex_);
      loop_stamps_.clear();
      scan_stamps_.clear();
      last_scan_tf_stamp_ = ros::Time();
      last_map_update_ = ros::Time();  // else no map until the clock passes the old update again
      last_summary_ = ros::Time();
      first_transform_ = true;
    }
    last_stamp_ = msg->header.stamp;

    geometry_msgs::TransformStamped base_laser, odom_base;
    try {
      base_laser = tf_buffer_.lookupTransform(base_frame_, msg->header.frame_id, msg->header.stamp, ros::Duration(0.2));
      odom_base = tf_buffer_.lookupTransform(odom_frame_, base_frame_, msg->header.stamp, ros::Duration(0.2));
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5.0, "slam_gmapping: skipping a scan on %s: no transform %s -> %s -> %s at %.3f: %s",
                        scan_sub_.getTopic().c_str(), msg->header.frame_id.c_str(), base_frame_.c_str(),
                        odom_frame_.c_str(), msg->header.stamp.toSec(), e.what());
      return;
    }
    const Eigen::Vector3d odom = toPose(odom_base);
    if (slam_ && !laser_checked_) {
      // A session loaded before any scan: its scans were taken with the laser where it was then.
      laser_checked_ = true;
      const Eigen::Vector3d now = toPose(base_laser);
      const auto* graph = dynamic_cast<const mbot::core::GraphSlam*>(slam_.get());
      const Eigen::Vector3d saved = graph ? graph->params().matcher.laser_pose : now;
      if ((now.head<2>() - saved.head<2>()).norm() > 0.01 || std::abs(mbot::core::normalizeAngle(now.z() - saved.z())) > 0.01) {
        ROS_WARN("slam_gmapping: the laser is at (%.3f, %.3f, %.3f) in %s, but at (%.3f, %.3f, %.3f) in the session loaded: "
                 "the session's pose is used for every scan",
                 now.x(), now.y(), now.z(), base_frame_.c_str(), saved.x(), saved.y(), saved.z());
      }
    }
    if (!slam_) {
      auto params = params_;
      params.matcher.laser_pose = toPose(base_laser);
      if (params.matcher.max_range <= 0.0) params.matcher.max_range = msg->range_max + 0.01;
      if (params.matcher.max_urange <= 0.0) params.matcher.max_urange = msg->range_max;
      try {
        std::lock_guard<std::mutex> lock(mutex_);
        if (backend_ == "rbpf") {
          params.tracking = graph_params_;  // the track's local SLAM (scan_odometry)
          slam_ = std::make_unique<mbot::core::RbpfSlam>(params);
        } else {
          auto graph = graph_params_;
          params.shareWith(graph);
          slam_ = std::make_unique<mbot::core::GraphSlam>(graph);
        }
      } catch (const std::invalid_argument& e) {
        ROS_FATAL("slam_gmapping: bad parameter ~%s", e.what());
        ros::shutdown();
        return;
      }
      ROS_INFO("slam_gmapping: starting a new map: %s backend%s, laser at (%.3f, %.3f, %.3f) in %s, maxUrange %.2f m, maxRange %.2f m",
               backend_.c_str(),
               backend_ == "rbpf" ? (" with " + std::to_string(params.particles) + " particles" +
                                     (params.scan_odometry ? " on scan odometry" : " on wheel odometry")).c_str() : "",
               params.matcher.laser_pose.x(), params.matcher.laser_pose.y(), params.matcher.laser_pose.z(),
               base_frame_.c_str(), params.matcher.max_urange, params.matcher.max_range);
    }
    bool updated, moved = false, outdated = false, resuming = false;
    Eigen::Vector3d before, after;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto* graph = dynamic_cast<mbot::core::GraphSlam*>(slam_.get());
      const bool was_resuming = graph && graph->resuming();
      if (was_resuming && !last_resume_try_.isZero() && msg->header.stamp >= last_resume_try_ &&
          (msg->header.stamp - last_resume_try_).toSec() < kResumeTryPeriod) {
        // Finding the robot on the whole map takes a while: one try every kResumeTryPeriod.
        resuming = true;
      }
    }
    if (resuming) {
      beatHeartbeat(msg->header.stamp);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto* graph = dynamic_cast<mbot::core::GraphSlam*>(slam_.get());
      const bool was_resuming = graph && graph->resuming();
      if (was_resuming) last_resume_try_ = msg->header.stamp;
      updated = slam_->processScan(odom, mbot::ros_glue::fromRos(*msg), msg->header.stamp.toSec());
      if (was_resuming) reportResume(*graph, msg->header.stamp);
      resuming = graph && graph->resuming();
      if (resuming) {
        // Not on the session's map yet: no map -> odom (it would be a guess), the map served as saved.
        if (slam_->mapOutdated()) publishMapUnlocked(msg->header.stamp);
      } else {
        // A closure found for the last node is solved after it, in the graph's own thread: a robot
        // that then stands still (an explorer back at its start) would keep the map of before the
        // correction until it moved linearUpdate on, and its report would judge that map.
        outdated = !updated && slam_->mapOutdated();
        // gmapping moves map -> odom at its updates only; the graph (and the rbpf with
        // scan_odometry) tracks every scan, and the graph's optimizer moves the current pose by
        // exactly its correction, so map -> odom follows both.
        if (updated || slam_->tracksEveryScan()) {
          before = map_to_odom_;
          after = map_to_odom_ = composePose(slam_->currentPose(), inversePose(odom));
          moved = true;
        }
      }
    }
    if (resuming) {
      beatHeartbeat(msg->header.stamp);
      return;
    }
    if (moved) publishScanTransform(msg->header.stamp, before, after, odom);
    if (weakest_pub_.getNumSubscribers() > 0) {
      std_msgs::Float64 weakest;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        weakest.data = slam_->trackingWeakestSigma();
      }
      if (weakest.data >= 0.0) weakest_pub_.publish(weakest);
    }
    beatHeartbeat(msg->header.stamp);
    if (!updated && !outdated) return;
    const auto* rbpf = dynamic_cast<const mbot::core::RbpfSlam*>(slam_.get());
    if (updated && rbpf) {
      std_msgs::Float64 entropy;
      entropy.data = rbpf->poseEntropy();
      entropy_pub_.publish(entropy);
    }
    if (last_map_update_.isZero() || (msg->header.stamp - last_map_update_).toSec() >= map_update_interval_) {
      publishMap(msg->header.stamp);
      last_map_update_ = msg->header.stamp;
    }
    if (updated) logSummary(msg->header.stamp);
  }

  // One line every kSummaryPeriod of (simulated) time: what the graph holds, so that a user who
  // leaves the robot running sees whether it keeps growing.
  void logSummary(const ros::Time& stamp) {
    if (last_summary_.isZero()) last_summary_ = stamp;
    if ((stamp - last_summary_).toSec() < kSummaryPeriod) return;
    last_summary_ = stamp;
    const auto* graph = dynamic_cast<const mbot::core::GraphSlam*>(slam_.get());
    if (!graph) return;
    const mbot::core::GraphSlamStats s = graph->stats();
    struct mallinfo2 heap = mallinfo2();
    ROS_INFO("slam_gmapping: %d nodes (%d revisits, %d of them with their scan freed, %d out of the optimization), "
             "%d submaps (%.1f MB), %d loop closures (%d of them measured again with what their submap saw, %d to the submap just behind the local map, %d in the graph), %d optimizations (last %.0f ms); "
             "closure search backlog %d nodes (at most %d); "
             "scans move odometry's prediction by %.1f mm (rms; %.1f mm where they pin it), so its prior weighs %.0f, "
             "it decides %.0f%% of what scans leave open, and the search window is +-%.2f m; "
             "heap %.1f MB in use, %.1f MB free",
             s.nodes, s.redundant_nodes, s.trimmed_nodes, s.merged_nodes, s.submaps, s.submap_bytes / 1e6,
             s.closures_accepted, s.closures_remeasured, s.closures_recent, s.loop_closures, s.optimizations, s.last_optimization_ms, s.closure_backlog,
             s.closure_backlog_max,
             1000.0 * s.innovation_rms, 1000.0 * s.pinned_innovation_rms, s.prior_weight, 100.0 * s.odometry_trust,
             s.search_window_m,
             (heap.uordblks + heap.hblkhd) / 1e6, heap.fordblks / 1e6);
  }

  // map -> odom as estimated from the scan at `stamp`, stamped with it, so that map -> base at the
  // scan's time is the pose SLAM gave that scan: the periodic broadcast (stamped ahead, as gmapping)
  // already covers that time with the estimate of the scan before. A stamp the broadcast has used
  // is skipped: tf2 keeps the first of two transforms with one stamp and warns of the second.
  // A change of the robot's pose above ~correction_threshold (a loop closure, another best
  // particle) is published on ~correction and logged at debug level.
  void publishScanTransform(const ros::Time& stamp, const Eigen::Vector3d& before, const Eigen::Vector3d& after,
                            const Eigen::Vector3d& odom) {
    // A scan processed long after its time (a lagging node, an old bag): tf listeners keep 10 s by
    // default and would warn of "data from the past"; the broadcast carries the estimate on.
    const bool recent = ros::Time::now() - stamp < ros::Duration(kMaxScanTransformAge);
    bool send;
    {
      std::lock_guard<std::mutex> lock(stamp_mutex_);
      send = recent && stamp > last_scan_tf_stamp_ &&
             std::find(loop_stamps_.begin(), loop_stamps_.end(), stamp) == loop_stamps_.end();
      if (send) {
        last_scan_tf_stamp_ = stamp;
        scan_stamps_.push_back(stamp);
        if (scan_stamps_.size() > kStampMemory) scan_stamps_.pop_front();
      }
    }
    if (send) broadcaster_.sendTransform(mapToOdomMsg(stamp, after));
    // The robot's pose moved by the change of map -> odom at its current odometry.
    const Eigen::Vector3d moved = relativePose(composePose(before, odom), composePose(after, odom));
    const Eigen::Vector3d change = composePose(after, inversePose(before));
    if (!first_transform_ && moved.head<2>().norm() > correction_threshold_) {
      ROS_DEBUG("slam_gmapping: the pose of the scan at %.3f corrected by %.3f m, %.2f deg (map -> odom moved)",
                stamp.toSec(), moved.head<2>().norm(), moved.z() * 180.0 / M_PI);
      geometry_msgs::TransformStamped c = mapToOdomMsg(stamp, change);
      c.child_frame_id = map_frame_;  // the map frame before the correction, in the map frame after it
      correction_pub_.publish(c);
    }
    first_transform_ = false;
  }

  geometry_msgs::TransformStamped mapToOdomMsg(const ros::Time& stamp, const Eigen::Vector3d& m) const {
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = map_frame_;
    t.child_frame_id = odom_frame_;
    t.transform.translation.x = m.x();
    t.transform.translation.y = m.y();
    t.transform.rotation.z = std::sin(m.z() / 2.0);
    t.transform.rotation.w = std::cos(m.z() / 2.0);
    return t;
  }

  // Tells a simulator running real_time_factor:=auto how far SLAM has got: the stamp of the scan
  // just processed (std_msgs/Header on /sim_heartbeat; see sim/pacing.py). Only on simulated time.
  void beatHeartbeat(const ros::Time& stamp) {
    if (!heartbeat_pub_) return;
    std_msgs::Header beat;
    beat.stamp = stamp;
    beat.frame_id = ros::this_node::getName();
    heartbeat_pub_.publish(beat);
  }

  // Called in the scan callback, the only thread that replaces slam_. The graph builds its map
  // under its own locks (graph_slam.h), so the node's lock is not held meanwhile: the map -> odom
  // broadcast, which takes it, goes on through a rebuild after an optimization (up to 0.45 s on a
  // recorded run of the 30 x 20 m simulated floor, during which it stood still before). The
  // particle filter's map is read under the lock. Built in a thread of its own instead, the map
  // cost the node 4% more CPU on ACES (two runs each way) for little more.
  void publishMap(const ros::Time& stamp) {
    if (!slam_) return;
    // Published as a shared message: one serialization for every subscriber, and dynamic_map
    // answers from the same message without another copy of megabytes.
    auto map = boost::make_shared<nav_msgs::OccupancyGrid>();
    mbot::core::OccupancyImage image;
    if (backend_ == "graph") {
      image = slam_->occupancy(occ_thresh_);
    } else {
      std::lock_guard<std::mutex> lock(mutex_);
      image = slam_->occupancy(occ_thresh_);
    }
    if (publish_updates_) {
      // Grown by blocks and never shrunk (but for a new map after the clock went back): each change
      // of size sends the whole map.
      const bool keep = last_map_ && stamp >= last_map_->header.stamp;
      image = mbot::core::paddedToBlocks(std::move(image), blockCells(image.resolution), keep ? &covered_ : nullptr);
      covered_ = mbot::core::frameCells(image);
    }
    mbot::ros_glue::toRos(std::move(image), *map);
    map->header.frame_id = map_frame_;
    map->header.stamp = stamp;
    map->info.map_load_time = stamp;
    {
      std::lock_guard<std::mutex> lock(map_mutex_);
      const bool whole = !publish_updates_ || sendsWhole(*map, stamp);
      if (whole) {
        map_pub_.publish(map);
        meta_pub_.publish(map->info);
        whole_sent_at_ = stamp;
      } else {
        publishUpdates(*map, stamp);
      }
      last_map_ = map;
    }
    // A map rebuild and an optimization allocate and free megabytes; glibc keeps freed pages in
    // the middle of the heap, so a node left running for hours would show its peaks, not its use.
    // Once a minute, or at once when much is free: every page given back faults in again when the
    // next grid is built (trimmed after every map, the page faults took 2% of the node's CPU on ACES).
    if (mallinfo2().fordblks > kTrimFreeBytes || last_trim_.isZero() || stamp < last_trim_ ||
        (stamp - last_trim_).toSec() >= kTrimPeriod) {
      malloc_trim(0);
      last_trim_ = stamp;
    }
  }

  /// With ~publish_updates: the map grows by blocks of this many cells (4 m), so that whole maps
  /// are sent seldom.
  static int blockCells(double resolution) { return std::max(1, static_cast<int>(std::lround(4.0 / resolution))); }

  /// With ~publish_updates: whether `map` goes whole (its size or origin changed,
  /// ~whole_map_period passed, or the clock has not moved on since the last whole map: its
  /// subscribers take an update stamped so for part of that map); map_mutex_ held.
  bool sendsWhole(const nav_msgs::OccupancyGrid& map, const ros::Time& stamp) {
    const auto& a = map.info;
    if (!last_map_ || whole_sent_at_.isZero() || stamp <= whole_sent_at_ ||
        (stamp - whole_sent_at_).toSec() >= whole_map_period_) {
      return true;
    }
    // Origins compared to a thousandth of a cell: the same block's origin comes out of the map's
    // own (floating) origin a few 1e-15 m apart from one map to the next.
    const auto& b = last_map_->info;
    const double tol = 1e-3 * b.resolution;
    return a.width != b.width || a.height != b.height || std::abs(a.resolution - b.resolution) > 1e-9 ||
           std::abs(a.origin.position.x - b.origin.position.x) > tol || std::abs(a.origin.position.y - b.origin.position.y) > tol;
  }

  /// What changed since the last map, as map_msgs/OccupancyGridUpdate windows on map_updates (the
  /// tiles of 16 x 16 cells that changed, runs of them along a row in one window); map_mutex_ held.
  void publishUpdates(const nav_msgs::OccupancyGrid& map, const ros::Time& stamp) {
    const int width = static_cast<int>(map.info.width), height = static_cast<int>(map.info.height);
    for (const auto& w : mbot::core::changedWindows(last_map_->data, map.data, width, height, kUpdateTile)) {
      map_msgs::OccupancyGridUpdate up;
      up.header.frame_id = map_frame_;
      up.header.stamp = stamp;
      up.x = w.x;
      up.y = w.y;
      up.width = w.width;
      up.height = w.height;
      up.data.reserve(static_cast<size_t>(w.width) * w.height);
      for (int r = w.y; r < w.y + w.height; ++r) {
        const auto row = map.data.begin() + static_cast<long>(r) * width;
        up.data.insert(up.data.end(), row + w.x, row + w.x + w.width);
      }
      updates_pub_.publish(up);
    }
  }

  // The map of the graph backend, published from within the scan callback's lock (publishMap
  // takes the node's lock for the rbpf only).
  void publishMapUnlocked(const ros::Time& stamp) {
    if (backend_ == "graph") publishMap(stamp);
  }

  // After a scan that tried to join a loaded session: says how it went (while it does not match,
  // why: as information at first, the robot may still move to where its view is not repeated; as
  // a warning after kResumeWarnAfter; one line when it matches).
  void reportResume(const mbot::core::GraphSlam& graph, const ros::Time& stamp) {
    resuming_ = graph.resuming();
    if (graph.resuming()) {
      if (resume_since_.isZero() || stamp < resume_since_) resume_since_ = stamp;
      const double trying = (stamp - resume_since_).toSec();
      if (trying < kResumeWarnAfter) {
        ROS_INFO_THROTTLE(5.0, "slam_gmapping: the robot is not found on the session's map %s yet: %s; trying again "
                          "every %.1f s", loaded_path_.c_str(), graph.resumeFailure().c_str(), kResumeTryPeriod);
      } else {
        ROS_WARN_THROTTLE(10.0, "slam_gmapping: the robot is not found on the session's map %s after %.0f s: %s",
                          loaded_path_.c_str(), trying, graph.resumeFailure().c_str());
      }
      return;
    }
    const Eigen::Vector3d p = graph.currentPose();
    ROS_INFO("slam_gmapping: the robot is at (%.2f, %.2f, %.2f rad) on the session's map %s (found %s); %s",
             p.x(), p.y(), p.z(), loaded_path_.c_str(), resume_how_.c_str(),
             graph.localizing() ? "localizing on it (mode localization: the graph does not grow)"
                                : "mapping goes on from there");
  }

  // Loads the session <filename>.posegraph in place of the current map, the robot placed as
  // resume() says. On failure the current map stays and the reason is logged; false.
  bool loadSession(const std::string& filename, const std::optional<Eigen::Vector3d>& start, bool at_dock,
                   bool localization, const std::string& how) {
    const std::string path = mbot::core::sessionPath(filename);
    std::unique_ptr<mbot::core::GraphSlam> loaded;
    std::string notes;
    try {
      const std::string bytes = mbot::core::readSessionFile(path);
      auto params = params_;
      auto graph = graph_params_;
      params.shareWith(graph);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (const auto* current = dynamic_cast<const mbot::core::GraphSlam*>(slam_.get())) {
          graph.matcher = current->params().matcher;  // the laser as this robot has it
        }
      }
      loaded = mbot::core::GraphSlam::loadSession(bytes, graph, &notes);
    } catch (const std::exception& e) {
      ROS_ERROR("slam_gmapping: cannot load the session %s: %s; %s", path.c_str(), e.what(),
                slam_ ? "the current map stays" : "starting a new map");
      return false;
    }
    if (!notes.empty()) ROS_WARN("slam_gmapping: session %s: %s", path.c_str(), notes.c_str());
    loaded->resume(at_dock && !start ? std::optional<Eigen::Vector3d>(loaded->firstPose()) : start, localization);
    const int nodes = loaded->updates();
    const bool resuming = loaded->resuming();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      slam_ = std::move(loaded);
      laser_checked_ = false;
      last_resume_try_ = resume_since_ = ros::Time();
      resuming_ = resuming;
      loaded_path_ = path;
      resume_how_ = how;
      last_map_update_ = ros::Time();
    }
    ROS_INFO("slam_gmapping: loaded the session %s (%d nodes); finding the robot on it %s", path.c_str(), nodes,
             how.c_str());
    return true;
  }

  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    const std::string frame = msg->header.frame_id.empty() || msg->header.frame_id[0] != '/'
                                  ? msg->header.frame_id : msg->header.frame_id.substr(1);
    std::lock_guard<std::mutex> lock(mutex_);
    auto* graph = dynamic_cast<mbot::core::GraphSlam*>(slam_.get());
    if (!graph || loaded_path_.empty() || !graph->localizing()) {
      ROS_WARN("slam_gmapping: a pose on %s ignored: it places the robot on a session's map in mode localization "
               "(~mode, or ~deserialize_map with LOCALIZE_AT_POSE); %s", initial_pose_sub_.getTopic().c_str(),
               graph && !loaded_path_.empty() ? "this node is mapping" : "no session is loaded");
      return;
    }
    if (!frame.empty() && frame != map_frame_) {
      ROS_WARN("slam_gmapping: a pose on %s in frame '%s' ignored: it must be in %s", initial_pose_sub_.getTopic().c_str(),
               frame.c_str(), map_frame_.c_str());
      return;
    }
    const Eigen::Vector3d pose(msg->pose.pose.position.x, msg->pose.pose.position.y, tf2::getYaw(msg->pose.pose.orientation));
    graph->resume(pose, true);
    resuming_ = true;
    last_resume_try_ = resume_since_ = ros::Time();
    resume_how_ = "near the pose given on " + initial_pose_sub_.getTopic();
    ROS_INFO("slam_gmapping: finding the robot on the session's map near (%.2f, %.2f, %.2f rad), given on %s", pose.x(),
             pose.y(), pose.z(), initial_pose_sub_.getTopic().c_str());
  }

  bool onSerialize(mbot_slam_navigation::SerializePoseGraph::Request& req,
                   mbot_slam_navigation::SerializePoseGraph::Response& res) {
    res.result = mbot_slam_navigation::SerializePoseGraph::Response::RESULT_FAILED_TO_WRITE_FILE;
    const std::string path = mbot::core::sessionPath(req.filename.empty() ? "map" : req.filename);
    std::lock_guard<std::mutex> lock(mutex_);  // no scan meanwhile
    auto* graph = dynamic_cast<mbot::core::GraphSlam*>(slam_.get());
    if (!graph) {
      ROS_ERROR("slam_gmapping: ~serialize_map: %s", slam_ ? "sessions are the graph backend's (~backend graph)"
                                                              : "nothing mapped yet");
      return true;
    }
    try {
      const std::size_t bytes = mbot::core::saveSessionFile(*graph, path);
      ROS_INFO("slam_gmapping: session saved to %s (%d nodes, %.1f MB)", path.c_str(), graph->updates(), bytes / 1e6);
      res.result = mbot_slam_navigation::SerializePoseGraph::Response::RESULT_SUCCESS;
    } catch (const std::exception& e) {
      ROS_ERROR("slam_gmapping: ~serialize_map: %s", e.what());
    }
    return true;
  }

  bool onDeserialize(mbot_slam_navigation::DeserializePoseGraph::Request& req,
                     mbot_slam_navigation::DeserializePoseGraph::Response& res) {
    using Req = mbot_slam_navigation::DeserializePoseGraph::Request;
    using Res = mbot_slam_navigation::DeserializePoseGraph::Response;
    if (req.filename.empty()) {
      ROS_ERROR("slam_gmapping: ~deserialize_map: no filename given");
      res.result = Res::RESULT_INVALID_FILENAME;
      return true;
    }
    if (backend_ != "graph") {
      ROS_ERROR("slam_gmapping: ~deserialize_map: sessions are the graph backend's (~backend graph)");
      res.result = Res::RESULT_UNDEFINED_FAILURE;
      return true;
    }
    const Eigen::Vector3d given(req.initial_pose.x, req.initial_pose.y, req.initial_pose.theta);
    std::optional<Eigen::Vector3d> start;
    bool dock = false, localization = false;
    std::string how;
    switch (req.match_type) {
      case Req::UNSET:
        how = "by matching the scans against the whole map";
        break;
      case Req::START_AT_FIRST_NODE:
        dock = true;
        how = "where it began (START_AT_FIRST_NODE)";
        break;
      case Req::START_AT_GIVEN_POSE:
      case Req::LOCALIZE_AT_POSE:
        start = given;
        localization = req.match_type == Req::LOCALIZE_AT_POSE;
        how = "near the initial_pose given";
        break;
      default:
        ROS_ERROR("slam_gmapping: ~deserialize_map: match_type %d is none of UNSET (0), START_AT_FIRST_NODE (1), "
                  "START_AT_GIVEN_POSE (2), LOCALIZE_AT_POSE (3)", req.match_type);
        res.result = Res::RESULT_UNDEFINED_FAILURE;
        return true;
    }
    res.result = loadSession(req.filename, start, dock, localization, how) ? Res::RESULT_SUCCESS
                                                                            : Res::RESULT_FAILED_TO_READ_FILE;
    return true;
  }

  bool onDynamicMap(nav_msgs::GetMap::Request&, nav_msgs::GetMap::Response& res) {
    std::lock_guard<std::mutex> lock(map_mutex_);
    if (!last_map_ || last_map_->data.empty()) return false;  // gmapping answers false until it has a map
    res.map = *last_map_;
    return true;
  }

  void publishTransformLoop() {
    mbot::ros_glue::SimRate rate(1.0 / transform_publish_period_);  // no polling of /clock
    ros::Time last_tf_time;
    while (ros::ok()) {
      Eigen::Vector3d m;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        m = map_to_odom_;
      }
      const ros::Time now = ros::Time::now();
      // Nothing new without /clock or while it stands still; nothing before the robot is found on a
      // loaded session's map.
      if (now.isZero() || now == last_tf_time || resuming_) {
        rate.sleep();
        continue;
      }
      last_tf_time = now;
      // Stamped ahead, as gmapping does, so that lookups at "now" find it.
      const ros::Time stamp = now + ros::Duration(tf_delay_ > 0.0 ? tf_delay_ : transform_publish_period_);
      {
        std::lock_guard<std::mutex> lock(stamp_mutex_);
        if (std::find(scan_stamps_.begin(), scan_stamps_.end(), stamp) != scan_stamps_.end()) {
          rate.sleep();  // a scan's estimate holds this stamp already
          continue;
        }
        loop_stamps_.push_back(stamp);
        if (loop_stamps_.size() > kStampMemory) loop_stamps_.pop_front();
      }
      broadcaster_.sendTransform(mapToOdomMsg(stamp, m));
      rate.sleep();
    }
  }

  ros::NodeHandle nh_, pnh_;
  // From ~ (core/slam_config.h, where their defaults and meanings are).
  std::string base_frame_, odom_frame_, map_frame_;
  double map_update_interval_ = 0.0, transform_publish_period_ = 0.0, occ_thresh_ = 0.0, tf_delay_ = 0.0;
  int throttle_scans_ = 1;
  int scan_queue_size_ = 1;
  mbot::core::RbpfParams params_;
  mbot::core::GraphSlamParams graph_params_;
  std::string backend_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Publisher map_pub_, meta_pub_, entropy_pub_, heartbeat_pub_, correction_pub_, weakest_pub_, updates_pub_;
  bool publish_updates_ = false;
  double whole_map_period_ = 60.0;  // [s]
  ros::Time whole_sent_at_;             // when `map` was last published whole (map_mutex_)
  mbot::core::GridWindow covered_;      // the frame's cells the last map covered (publish_updates)
  static constexpr int kUpdateTile = 16;  // [cells] the tiles of map_updates' windows
  ros::Subscriber scan_sub_, initial_pose_sub_;
  ros::ServiceServer map_srv_, serialize_srv_, deserialize_srv_;
  // Sessions (slam_config.h).
  std::string session_file_, mode_, save_session_on_exit_;
  std::optional<Eigen::Vector3d> map_start_pose_;
  bool map_start_at_dock_ = false;
  bool laser_checked_ = true;       // the laser's pose compared with a loaded session's
  std::string loaded_path_, resume_how_;  // the session loaded and how the robot is found on it
  ros::Time last_resume_try_;             // the scan that last tried to join a loaded session
  ros::Time resume_since_;                // the first scan that tried
  // Read by the map -> odom broadcast: until the robot is found on a loaded session's map, no
  // map -> odom is sent (any would be a guess that move_base and amcl's users would trust).
  std::atomic<bool> resuming_{false};
  static constexpr double kResumeTryPeriod = 0.5;   // [s] of scan time between tries
  static constexpr double kResumeWarnAfter = 10.0;  // [s] of trying before it is a warning
  std::mutex mutex_, map_mutex_;
  // Stamps of map -> odom lately sent by the broadcast loop and by the scan callback (stamp_mutex_).
  static constexpr std::size_t kStampMemory = 256;
  static constexpr std::size_t kTrimFreeBytes = 64u << 20;  // free heap [bytes] given back at once
  static constexpr double kTrimPeriod = 60.0;                 // [s] between trims otherwise
  static constexpr double kMaxScanTransformAge = 5.0;  // [s]
  std::mutex stamp_mutex_;
  std::deque<ros::Time> loop_stamps_, scan_stamps_;
  ros::Time last_scan_tf_stamp_;
  bool first_transform_ = true;
  double correction_threshold_ = 0.0;
  std::unique_ptr<mbot::core::SlamBackend> slam_;  // replaced in the scan callback only
  Eigen::Vector3d map_to_odom_ = Eigen::Vector3d::Zero();
  nav_msgs::OccupancyGrid::ConstPtr last_map_;  // the newest map (whole or sent as updates); never changed after
  ros::Time last_stamp_, last_map_update_;
  long scan_count_ = 0;
  mbot::ros_glue::SeqGapCounter scan_gaps_;  // scans roscpp dropped from the full queue
  static constexpr double kSummaryPeriod = 300.0;  // [s]
  ros::Time last_summary_;
  ros::Time last_trim_;  // when the heap was last trimmed (publishMap)
  std::thread tf_thread_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "slam_gmapping");
  try {
    SlamGmappingNode node;
    ros::spin();
    node.saveOnExit();
  } catch (const mbot::core::ParamError&) {
    return 1;  // already logged
  }
  return 0;
}
