#include "costmap_ros.h"

#include <cmath>

#include <geometry_msgs/PolygonStamped.h>
#include <map_msgs/OccupancyGridUpdate.h>
#include <tf2/utils.h>

#include "ros_conversions.h"

namespace mbot {
namespace ros_glue {

CostmapROS::CostmapROS(const std::string& name, tf2_ros::Buffer& tf, std::function<void(const ros::Time&)> beat)
    : name_(name), tf_(tf), beat_(std::move(beat)) {
  ros::NodeHandle nh, pnh("~");
  XmlRpc::XmlRpcValue values;
  if (!pnh.getParam(name, values)) values = XmlRpc::XmlRpcValue();
  const auto warn = [](const std::string& text) { ROS_WARN("%s", text.c_str()); };
  core::CostmapConfig config = core::readCostmapConfig(name, fromXmlRpc(values), warn, ros::this_node::getName());
  for (auto& f : config.filters) {
    if (!f.mask_topic.empty()) f.mask_topic = ros::names::resolve(f.mask_topic);  // named so in messages
  }
  layered_ = std::make_unique<core::LayeredCostmap>(config, warn);
  // A new subscriber gets the whole grid at the next publication (costmap_2d's onNewSubscription).
  costmap_pub_ = pnh.advertise<nav_msgs::OccupancyGrid>(
      name + "/costmap", 1, [this](const ros::SingleSubscriberPublisher&) { send_full_ = true; }, ros::SubscriberStatusCallback(),
      ros::VoidConstPtr(), true);
  updates_pub_ = pnh.advertise<map_msgs::OccupancyGridUpdate>(name + "/costmap_updates", 1);
  footprint_pub_ = pnh.advertise<geometry_msgs::PolygonStamped>(name + "/footprint", 1);
  if (config.static_layer) {
    subscribers_.push_back(nh.subscribe(config.static_layer->map_topic, 1, &CostmapROS::onMap, this));
    ROS_INFO("%s: static layer waits for a map on %s", name.c_str(), subscribers_.back().getTopic().c_str());
    if (config.static_layer->subscribe_to_updates) {
      map_updates_sub_ = nh.subscribe(config.static_layer->map_topic + "_updates", 100, &CostmapROS::onMapUpdate, this);
    }
  }
  mask_received_ = std::vector<std::atomic<bool>>(config.filters.size());
  for (std::size_t i = 0; i < config.filters.size(); ++i) {
    const core::FilterConfig& f = config.filters[i];
    if (!f.error.empty()) {
      ROS_ERROR("%s: filter %s (%s) is left out: %s. The costmap goes on without it.", name.c_str(), f.name.c_str(),
                f.type.c_str(), f.error.c_str());
    } else if (!f.enabled) {
      ROS_INFO("%s: filter %s is disabled (enabled: false)", name.c_str(), f.name.c_str());
    } else if (!f.mask_topic.empty()) {
      subscribers_.push_back(nh.subscribe<nav_msgs::OccupancyGrid>(
          f.mask_topic, 1, [this, i](const nav_msgs::OccupancyGrid::ConstPtr& m) { onMask(m, i); }));
      ROS_INFO("%s: %s filter %s waits for its mask on %s", name.c_str(),
               f.kind == core::FilterConfig::Kind::kSpeed ? "speed" : "keep-out", f.name.c_str(),
               subscribers_.back().getTopic().c_str());
    } else {
      ROS_INFO("%s: keep-out filter %s: %zu zones from prohibition_areas", name.c_str(), f.name.c_str(), f.zones.size());
    }
  }
  // A mask that never comes (its map_server failed, or another topic) is said once, not waited for.
  mask_watch_ = nh.createWallTimer(ros::WallDuration(10.0), [this](const ros::WallTimerEvent&) {
    const auto& filters = layered_->config().filters;
    for (std::size_t i = 0; i < filters.size(); ++i) {
      if (filters[i].error.empty() && filters[i].enabled && !filters[i].mask_topic.empty() && !mask_received_[i]) {
        ROS_WARN("%s: filter %s: no mask on %s after 10 s; the costmap goes on without it until one arrives (is a "
                 "map_server serving the mask there? e.g. keepout_mask:=FILE.yaml)",
                 name_.c_str(), filters[i].name.c_str(), ros::names::resolve(filters[i].mask_topic).c_str());
      }
    }
  }, true);
  if (config.obstacle_layer) {
    for (std::size_t i = 0; i < config.obstacle_layer->sources.size(); ++i) {
      subscribers_.push_back(nh.subscribe<sensor_msgs::LaserScan>(
          config.obstacle_layer->sources[i].topic, 5, [this, i](const sensor_msgs::LaserScan::ConstPtr& m) { onScan(m, i); }));
    }
  }
  if (config.update_frequency > 0) {
    update_timer_ = nh.createTimer(ros::Duration(1.0 / config.update_frequency), [this](const ros::TimerEvent&) {
      if (active_) update();
    });
  }
  if (config.publish_frequency > 0) {
    publish_timer_ = nh.createTimer(ros::Duration(1.0 / config.publish_frequency), [this](const ros::TimerEvent&) {
      if (active_ && ever_updated_) publish();
    });
  }
}

void CostmapROS::onMap(const nav_msgs::OccupancyGrid::ConstPtr& msg) {
  const auto& info = msg->info;
  if (info.width == 0 || info.height == 0 || msg->data.size() != static_cast<std::size_t>(info.width) * info.height) {
    ROS_ERROR_THROTTLE(10, "%s: map on %s has %zu cells for %u x %u; ignored", name_.c_str(), subscribers_[0].getTopic().c_str(),
                       msg->data.size(), info.width, info.height);
    return;
  }
  std::string frame = msg->header.frame_id;
  while (!frame.empty() && frame[0] == '/') frame.erase(0, 1);
  const auto& c = config();
  if (!frame.empty() && frame != c.global_frame) {
    ROS_WARN_THROTTLE(30, "%s: the map is in frame \"%s\" but global_frame is \"%s\"; used as if it were in %s", name_.c_str(),
                      frame.c_str(), c.global_frame.c_str(), c.global_frame.c_str());
  }
  if (std::abs(tf2::getYaw(info.origin.orientation)) > 1e-6) {
    ROS_WARN_THROTTLE(30, "%s: the map origin is rotated; costmaps use its position only", name_.c_str());
  }
  {
    std::lock_guard<std::mutex> guard(mutex_);
    // updates that came before this map on the other connection, newer than it
    const auto newer = map_log_.whole(static_cast<int64_t>(msg->header.stamp.toNSec()),
                                      static_cast<int64_t>(ros::Time::now().toNSec()));
    if (!newer) return;  // stale: a latched map older than the one held
    layered_->setMap(msg->data, static_cast<int>(info.width), static_cast<int>(info.height),
                     {info.origin.position.x, info.origin.position.y}, info.resolution);
    for (const auto& u : *newer) layered_->patchMap(u.data, u.window.x, u.window.y, u.window.width, u.window.height);
  }
  reportFilterErrors();
}

void CostmapROS::onMapUpdate(const map_msgs::OccupancyGridUpdate::ConstPtr& msg) {
  // Kept for the next whole map as well: it may be on its way on the other connection, older than
  // this update, and must not write over it.
  core::MapUpdate u{static_cast<int64_t>(msg->header.stamp.toNSec()),
                    core::GridWindow{msg->x, msg->y, static_cast<int>(msg->width), static_cast<int>(msg->height)},
                    msg->data};
  std::lock_guard<std::mutex> guard(mutex_);
  if (map_log_.update(u)) {
    // One that does not fit (costmap_2d's StaticLayer would write past its map) waits for the
    // whole map of the new size.
    layered_->patchMap(u.data, u.window.x, u.window.y, u.window.width, u.window.height);
  }
}

void CostmapROS::reportFilterErrors() {
  std::vector<std::string> errors;
  {
    std::lock_guard<std::mutex> guard(mutex_);
    errors = layered_->takeFilterErrors();
  }
  for (const auto& e : errors) ROS_ERROR("%s: filter %s", name_.c_str(), e.c_str());
}

void CostmapROS::onMask(const nav_msgs::OccupancyGrid::ConstPtr& msg, std::size_t index) {
  const core::FilterConfig& f = config().filters[index];
  const std::string topic = ros::names::resolve(f.mask_topic);
  std::string frame = msg->header.frame_id;
  while (!frame.empty() && frame[0] == '/') frame.erase(0, 1);
  const auto& info = msg->info;
  std::string why;
  if (frame != config().global_frame) {
    why = "the mask is in frame \"" + frame + "\", the costmap in \"" + config().global_frame +
          "\" (serve the mask with frame_id " + config().global_frame + ")";
  } else if (std::abs(tf2::getYaw(info.origin.orientation)) > 1e-6) {
    why = "the mask's origin is rotated";
  } else {
    try {
      std::lock_guard<std::mutex> guard(mutex_);
      layered_->setFilterMask(index, msg->data, static_cast<int>(info.width), static_cast<int>(info.height),
                              {info.origin.position.x, info.origin.position.y}, info.resolution);
    } catch (const std::invalid_argument& e) {
      why = e.what();
    }
  }
  if (!why.empty()) {
    ROS_ERROR("%s: filter %s: the mask on %s is ignored: %s. The costmap goes on without it.", name_.c_str(),
              f.name.c_str(), topic.c_str(), why.c_str());
    return;
  }
  mask_received_[index] = true;
  std::string zones;
  {
    std::lock_guard<std::mutex> guard(mutex_);
    const auto& names = layered_->filterMask(index).zoneNames();
    for (std::size_t k = 0; k < names.size() && k < 5; ++k) zones += (zones.empty() ? "" : ", ") + names[k];
    if (names.size() > 5) zones += " and " + std::to_string(names.size() - 5) + " more";
  }
  ROS_INFO("%s: %s filter %s: a mask of %u x %u cells from %s; zones: %s", name_.c_str(),
           f.kind == core::FilterConfig::Kind::kSpeed ? "speed" : "keep-out", f.name.c_str(), info.width, info.height,
           topic.c_str(), zones.empty() ? "none" : zones.c_str());
}

std::string CostmapROS::keepoutZoneAt(const Eigen::Vector2d& p) const {
  std::lock_guard<std::mutex> guard(mutex_);
  return layered_->keepoutZoneAt(p);
}

core::LayeredCostmap::SpeedLimit CostmapROS::speedLimitAt(const Eigen::Vector3d& pose) const {
  std::lock_guard<std::mutex> guard(mutex_);
  return layered_->speedLimitAt(pose);
}

void CostmapROS::onScan(const sensor_msgs::LaserScan::ConstPtr& msg, std::size_t source) {
  if (!active_) return;
  const auto& src = config().obstacle_layer->sources[source];
  std::string frame = src.sensor_frame.empty() ? msg->header.frame_id : src.sensor_frame;
  while (!frame.empty() && frame[0] == '/') frame.erase(0, 1);
  geometry_msgs::TransformStamped t;
  try {
    t = tf_.lookupTransform(config().global_frame, frame, msg->header.stamp, ros::Duration(0.2));
  } catch (const tf2::TransformException& e) {
    ROS_WARN_THROTTLE(5, "%s: observation source %s (topic %s): no transform from \"%s\" to \"%s\" at the scan time: %s",
                      name_.c_str(), src.name.c_str(), src.topic.c_str(), frame.c_str(), config().global_frame.c_str(), e.what());
    return;
  }
  const Eigen::Vector3d pose(t.transform.translation.x, t.transform.translation.y, tf2::getYaw(t.transform.rotation));
  const core::LaserScan scan = fromRos(*msg);
  std::lock_guard<std::mutex> guard(mutex_);
  layered_->addScan(source, msg->header.stamp.toSec(), pose, t.transform.translation.z, scan);
}

std::optional<Eigen::Vector3d> CostmapROS::lookupRobotPose() {
  const auto& c = config();
  geometry_msgs::TransformStamped t;
  try {
    t = tf_.lookupTransform(c.global_frame, c.robot_base_frame, ros::Time(0), ros::Duration(0.1));
  } catch (const tf2::TransformException& e) {
    std::lock_guard<std::mutex> guard(mutex_);
    tf_problem_ = "no transform from " + c.robot_base_frame + " to " + c.global_frame + ": " + e.what();
    return std::nullopt;
  }
  if (beat_) beat_(t.header.stamp);
  const double age = (ros::Time::now() - t.header.stamp).toSec();
  std::lock_guard<std::mutex> guard(mutex_);
  if (!t.header.stamp.isZero() && age > c.transform_tolerance) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "the transform from %s to %s is %.2f s old, more than transform_tolerance %.2f s",
                  c.robot_base_frame.c_str(), c.global_frame.c_str(), age, c.transform_tolerance);
    tf_problem_ = buf;
    return std::nullopt;
  }
  tf_problem_.clear();
  return Eigen::Vector3d(t.transform.translation.x, t.transform.translation.y, tf2::getYaw(t.transform.rotation));
}

std::string CostmapROS::tfProblem() const {
  std::lock_guard<std::mutex> guard(mutex_);
  return tf_problem_;
}

bool CostmapROS::update() {
  const auto pose = lookupRobotPose();
  if (!pose) {
    ROS_WARN_THROTTLE(5, "%s: not updated: %s", name_.c_str(), tfProblem().c_str());
    return false;
  }
  {
    std::lock_guard<std::mutex> guard(mutex_);
    if (!layered_->ready()) {
      ROS_WARN_THROTTLE(10, "%s: waiting for the first map on %s", name_.c_str(), subscribers_[0].getTopic().c_str());
      return false;
    }
    const int w = layered_->master().width(), h = layered_->master().height();
    const Eigen::Vector2d before = layered_->master().origin();
    const core::CellWindow changed = layered_->update(*pose);
    const auto& m = layered_->master();
    if (m.width() != w || m.height() != h || (m.origin() - before).norm() > 1e-9) send_full_ = true;
    unpublished_ = unpublished_.unite(changed);
    ever_updated_ = true;
  }
  publishFootprint(*pose);
  return true;
}

std::pair<bool, std::string> CostmapROS::isCurrent() {
  std::lock_guard<std::mutex> guard(mutex_);
  if (!ever_updated_) return {false, name_ + " has not been updated yet" + (tf_problem_.empty() ? "" : ": " + tf_problem_)};
  const auto stale = layered_->staleSources(ros::Time::now().toSec());
  if (stale.empty()) return {true, ""};
  std::string names;
  for (const auto& s : stale) names += (names.empty() ? "" : ", ") + s;
  return {false, name_ + ": observation source " + names};
}

void CostmapROS::publish() {
  nav_msgs::OccupancyGrid grid;
  map_msgs::OccupancyGridUpdate up;
  bool send_update = false;
  {
    std::lock_guard<std::mutex> guard(mutex_);
    const auto& m = layered_->master();
    const ros::Time stamp = ros::Time::now();
    grid.header.frame_id = config().global_frame;
    grid.header.stamp = stamp;
    grid.info.map_load_time = stamp;
    grid.info.resolution = static_cast<float>(m.resolution());
    grid.info.width = static_cast<uint32_t>(m.width());
    grid.info.height = static_cast<uint32_t>(m.height());
    grid.info.origin.position.x = m.origin().x();
    grid.info.origin.position.y = m.origin().y();
    grid.info.origin.orientation.w = 1.0;
    const auto data = m.toOccupancyData();
    grid.data.assign(data.begin(), data.end());
    // The changed window as costmap_updates (the whole grid when always_send_full_costmap).
    core::CellWindow w = config().always_send_full_costmap || send_full_ ? core::CellWindow{0, 0, m.width(), m.height()}
                                                                         : unpublished_.grown(0, m.width(), m.height());
    if (!w.empty() && updates_pub_.getNumSubscribers() > 0) {
      up.header = grid.header;
      up.x = w.x0;
      up.y = w.y0;
      up.width = static_cast<uint32_t>(w.x1 - w.x0);
      up.height = static_cast<uint32_t>(w.y1 - w.y0);
      up.data.reserve(static_cast<std::size_t>(up.width) * up.height);
      for (int y = w.y0; y < w.y1; ++y) {
        const auto row = data.begin() + static_cast<long>(y) * m.width();
        up.data.insert(up.data.end(), row + w.x0, row + w.x1);
      }
      send_update = true;
    }
    unpublished_ = core::CellWindow{};
    send_full_ = false;
  }
  // The whole grid every time (a difference from ROS, which sends it on a resize only): clients
  // that read only ~costmap (our explorer, explore_lite without costmap_updates_topic) stay current.
  costmap_pub_.publish(grid);
  if (send_update) updates_pub_.publish(up);
}

void CostmapROS::publishFootprint(const Eigen::Vector3d& pose) {
  if (footprint_pub_.getNumSubscribers() == 0) return;
  geometry_msgs::PolygonStamped msg;
  msg.header.stamp = ros::Time::now();
  msg.header.frame_id = config().global_frame;
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  for (const auto& p : config().footprint) {
    geometry_msgs::Point32 q;
    q.x = static_cast<float>(pose.x() + c * p.x() - s * p.y());
    q.y = static_cast<float>(pose.y() + s * p.x() + c * p.y());
    msg.polygon.points.push_back(q);
  }
  footprint_pub_.publish(msg);
}

void CostmapROS::resetLayers(const std::optional<Eigen::Vector3d>& keep) {
  std::lock_guard<std::mutex> guard(mutex_);
  layered_->resetObstacles(keep);
}

}  // namespace ros_glue
}  // namespace mbot
