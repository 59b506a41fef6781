// move_base (roscpp): the actionlib server, tf, the costmaps' ROS side, the recoveries' motions and
// the publishers, around the core's state machine (core/move_base_fsm.h: planning, controlling,
// clearing, patience, oscillation, the recoveries' order), costmaps, global planner and trajectory
// controller.
//
// Interfaces as ROS's move_base: action `move_base` (move_base_msgs/MoveBaseAction),
// `move_base_simple/goal`, `cmd_vel`, `odom` (for the robot's velocity), services `~make_plan`
// (nav_msgs/GetPlan) and `~clear_costmaps` (std_srvs/Empty); costmaps under `~global_costmap` and
// `~local_costmap`; plans on `~NavfnROS/plan` (and `~plan`), `~TrajectoryPlannerROS/local_plan` and
// `~TrajectoryPlannerROS/global_plan`; the goal in use on `~current_goal`. Both costmaps beat
// /sim_heartbeat with the robot pose's stamp under simulated time (the simulator's auto pacing).
//
// Differences from ROS, on purpose: a failed replan while moving stops the robot (ROS keeps
// following the old plan, possibly through a new obstacle); oscillation detection is on by default;
// `~make_plan` answers while a goal is active; a back-up recovery is among the defaults; every
// abort says why; `~progress_timeout` (60 s) bounds a goal that driving about never brings nearer
// (a robot circling a person who stands on its goal), which ROS would pursue for ever.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <actionlib/server/simple_action_server.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <nav_msgs/GetPlan.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_srvs/Empty.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "costmap_ros.h"
#include "sim_rate.h"
#include "mbot_slam_navigation/core/global_planner.h"
#include "mbot_slam_navigation/core/move_base_config.h"
#include "mbot_slam_navigation/core/move_base_fsm.h"
#include "mbot_slam_navigation/core/trajectory_controller.h"
#include "ros_conversions.h"

namespace mbot {
namespace {

using Vec3 = Eigen::Vector3d;
using Path2 = std::vector<Eigen::Vector2d>;
using ros_glue::SimRate;
std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[1024];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buf, sizeof buf, f, args);
  va_end(args);
  return buf;
}

geometry_msgs::PoseStamped poseStamped(const std_msgs::Header& header, double x, double y, double yaw) {
  geometry_msgs::PoseStamped p;
  p.header = header;
  p.pose.position.x = x;
  p.pose.position.y = y;
  p.pose.orientation.z = std::sin(yaw / 2.0);
  p.pose.orientation.w = std::cos(yaw / 2.0);
  return p;
}

Vec3 compose(const Vec3& a, const Vec3& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {a.x() + c * b.x() - s * b.y(), a.y() + s * b.x() + c * b.y(), std::atan2(std::sin(a.z() + b.z()), std::cos(a.z() + b.z()))};
}


class MoveBase {
 public:
  MoveBase()
      : tf_(ros::Duration(30.0)),
        listener_(tf_),
        server_(makeServer()) {
    ros::NodeHandle pnh("~");
    if (ros::Time::isSimTime()) heartbeat_pub_ = nh_.advertise<std_msgs::Header>("/sim_heartbeat", 10);
    auto beat = [this](const ros::Time& stamp) { beatHeartbeat(stamp); };
    global_ = std::make_unique<ros_glue::CostmapROS>("global_costmap", tf_, beat);
    local_ = std::make_unique<ros_glue::CostmapROS>("local_costmap", tf_, beat);
    XmlRpc::XmlRpcValue values;
    if (!pnh.getParam("", values)) values = XmlRpc::XmlRpcValue();
    config_ = core::readMoveBaseConfig(ros_glue::fromXmlRpc(values), ros::this_node::getName(),
                                       [](const std::string& t) { ROS_WARN("%s", t.c_str()); },
                                       local_->config().circumscribed_radius);
    // lethal_cost 0: the global costmap's contact cost, set before each plan (it follows the map's resolution).
    auto_lethal_cost_ = config_.planner.lethal_cost == 0;
    if (auto_lethal_cost_) config_.planner.lethal_cost = core::cost::kInscribed;
    planner_ = std::make_unique<core::GlobalPlanner>(config_.planner);
    service_planner_ = std::make_unique<core::GlobalPlanner>(config_.planner);  // ~make_plan, not racing the loop
    controller_ = std::make_unique<core::TrajectoryController>(config_.local, config_.local_ros, local_->config().footprint);
    fsm_ = std::make_unique<core::MoveBaseStateMachine>(config_);

    cmd_pub_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    plan_pub_ = pnh.advertise<nav_msgs::Path>(config_.global_ns + "/plan", 1, true);
    generic_plan_pub_ = pnh.advertise<nav_msgs::Path>("plan", 1, true);
    local_plan_pub_ = pnh.advertise<nav_msgs::Path>(config_.local_ns + "/local_plan", 1);
    local_global_plan_pub_ = pnh.advertise<nav_msgs::Path>(config_.local_ns + "/global_plan", 1);
    goal_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("current_goal", 1, true);
    action_goal_pub_ = nh_.advertise<move_base_msgs::MoveBaseActionGoal>("move_base/goal", 1);
    odom_sub_ = nh_.subscribe("odom", 1, &MoveBase::onOdom, this);
    simple_goal_sub_ = nh_.subscribe("move_base_simple/goal", 1, &MoveBase::onSimpleGoal, this);
    make_plan_srv_ = pnh.advertiseService("make_plan", &MoveBase::onMakePlan, this);
    clear_srv_ = pnh.advertiseService("clear_costmaps", &MoveBase::onClearCostmaps, this);
    if (config_.shutdown_costmaps) {
      global_->stop();
      local_->stop();
    }
    server_->start();
    clock_watch_ = nh_.createSteadyTimer(ros::WallDuration(0.2), [this](const ros::SteadyTimerEvent&) { watchClock(); });
    std::string recoveries;
    for (const auto& r : config_.recoveries) recoveries += (recoveries.empty() ? "" : ", ") + r.name;
    ROS_INFO("move_base ready: global planner %s (%s), local planner %s%s, recoveries %s", config_.global_type.c_str(),
             config_.planner.use_astar ? "A*" : "Dijkstra", config_.local_type.c_str(), config_.local.dwa ? " (DWA)" : "",
             config_.recovery_behavior_enabled ? recoveries.c_str() : "disabled");
  }

 private:
  // --- inputs -------------------------------------------------------------------------------------
  void beatHeartbeat(const ros::Time& stamp) {
    if (!heartbeat_pub_ || stamp.isZero()) return;
    std_msgs::Header h;
    h.stamp = stamp;
    h.frame_id = ros::this_node::getName();
    heartbeat_pub_.publish(h);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    std::lock_guard<std::mutex> guard(velocity_mutex_);
    velocity_ = Vec3(msg->twist.twist.linear.x, msg->twist.twist.linear.y, msg->twist.twist.angular.z);
  }

  Vec3 velocity() {
    std::lock_guard<std::mutex> guard(velocity_mutex_);
    return velocity_;
  }

  void onSimpleGoal(const geometry_msgs::PoseStamped::ConstPtr& msg) {
    ROS_INFO("move_base: a goal from move_base_simple/goal (rviz 2D Nav Goal)");
    move_base_msgs::MoveBaseActionGoal goal;
    goal.header.stamp = ros::Time::now();
    goal.goal.target_pose = *msg;
    action_goal_pub_.publish(goal);
  }

  /// The pose as (x, y, yaw) in `frame` (tf2 for another frame), or nullopt with `why`.
  /// heading_required false (make_plan requests, which often leave the orientation all zero) reads a
  /// zero quaternion as yaw 0 instead of refusing it.
  std::optional<Vec3> inFrame(const geometry_msgs::PoseStamped& pose, const std::string& frame, std::string& why,
                              bool heading_required = true) {
    const auto& o = pose.pose.orientation;
    double yaw = 0.0;
    if (heading_required || o.x != 0.0 || o.y != 0.0 || o.z != 0.0 || o.w != 0.0) {
      const auto [y, note] = ros_glue::planarYaw(o.x, o.y, o.z, o.w, "the goal orientation");
      if (!y) {
        why = note;
        return std::nullopt;
      }
      if (!note.empty()) ROS_WARN("move_base: %s", note.c_str());
      yaw = *y;
    }
    Vec3 goal(pose.pose.position.x, pose.pose.position.y, yaw);
    if (!goal.allFinite()) {
      why = "the goal position is not finite";
      return std::nullopt;
    }
    std::string source = pose.header.frame_id;
    while (!source.empty() && source[0] == '/') source.erase(0, 1);
    if (source.empty()) {
      why = "the goal has an empty frame_id";
      return std::nullopt;
    }
    if (source != frame) {
      geometry_msgs::TransformStamped t;
      try {
        t = tf_.lookupTransform(frame, source, ros::Time(0), ros::Duration(0.5));
      } catch (const tf2::TransformException& e) {
        why = "cannot transform the goal from frame \"" + source + "\" to \"" + frame + "\": " + e.what();
        return std::nullopt;
      }
      goal = compose(Vec3(t.transform.translation.x, t.transform.translation.y, tf2::getYaw(t.transform.rotation)), goal);
    }
    return goal;
  }

  // --- planning -------------------------------------------------------------------------------------
  /// Plans on the global costmap; false with `why` when there is no plan. `used_lethal_cost`: the
  /// lethal_cost the plan was made with.
  bool plan(core::GlobalPlanner& planner, const Vec3& start, const Vec3& goal, Path2& path, std::string& why,
            int* used_lethal_cost = nullptr) {
    double resolution;
    core::Plan p;
    int lethal;
    {
      auto guard = global_->lock();
      lethal = lethalCost();
      // A way with room to spare where it is not much longer (in clutter a plan through a gap the
      // footprint clears by a centimetre is a slow one to drive), else one where the footprint just
      // clears. Not when the robot or the goal stands where there is no such room: that plan would
      // start or end elsewhere.
      const core::Costmap& m = global_->master();
      const core::Cell sc = m.worldToCell(start.head<2>()), gc = m.worldToCell(goal.head<2>());
      int roomy = auto_lethal_cost_ ? global_->roomyCost() : lethal;
      if (!m.contains(sc) || !m.contains(gc) || m.cost(sc) >= roomy || m.cost(gc) >= roomy) roomy = lethal;
      p = core::planPreferringRoom(planner, m, start.head<2>(), goal.head<2>(), roomy, lethal, core::kMaxRoomyDetour_m,
                                   &lethal);
      if (p.status == core::PlanStatus::kNoPath && auto_lethal_cost_ && lethal < core::cost::kInscribed) {
        // No way keeps the footprint clear at every cell centre: one through cells where it may
        // touch (ROS's rule) is still worth trying, the robot is not held to cell centres. (A
        // lethal_cost the user set is kept, as global_planner keeps it.)
        planner.setLethalCost(core::cost::kInscribed);
        core::Plan loose = planner.makePlan(global_->master(), start.head<2>(), goal.head<2>());
        if (loose.status == core::PlanStatus::kOk) {
          ROS_INFO_THROTTLE(10.0, "move_base: no way with the footprint clear at every cell; planning through cells where "
                                  "it may touch an obstacle (lethal_cost 253)");
          p = std::move(loose);
          lethal = core::cost::kInscribed;
        }
      }
      resolution = global_->master().resolution();
    }
    if (used_lethal_cost) *used_lethal_cost = lethal;
    if (p.status != core::PlanStatus::kOk) {
      why = std::string(core::toString(p.status)) + ": " + p.message;
      return false;
    }
    path = std::move(p.path);
    // navfn ends its plan on the goal pose itself.
    if (!path.empty() && (path.back() - goal.head<2>()).norm() <= resolution) path.push_back(goal.head<2>());
    return true;
  }

  void publishPath(const std::vector<ros::Publisher*>& pubs, const Path2& path, const std::string& frame,
                   std::optional<double> yaw = std::nullopt) {
    nav_msgs::Path msg;
    msg.header.stamp = ros::Time::now();
    msg.header.frame_id = frame;
    for (std::size_t i = 0; i < path.size(); ++i) {
      msg.poses.push_back(poseStamped(msg.header, path[i].x(), path[i].y(), yaw && i + 1 == path.size() ? *yaw : 0.0));
    }
    for (auto* pub : pubs) pub->publish(msg);
  }

  bool onMakePlan(nav_msgs::GetPlan::Request& req, nav_msgs::GetPlan::Response& resp) {
    const std::string frame = global_->config().global_frame;
    resp.plan.header.frame_id = frame;
    resp.plan.header.stamp = ros::Time::now();
    std::string why;
    std::optional<Vec3> start;
    if (!req.start.header.frame_id.empty()) {
      start = inFrame(req.start, frame, why, false);
    } else {
      start = global_->lookupRobotPose();
      if (!start) why = global_->tfProblem();
    }
    const auto goal = start ? inFrame(req.goal, frame, why, false) : std::nullopt;
    if (!start || !goal) {
      ROS_ERROR("make_plan: %s", why.c_str());
      return true;
    }
    if (const std::string zone = keepoutZoneAt(*goal); !zone.empty()) {
      ROS_WARN("make_plan: no plan to (%.2f, %.2f): it lies in keep-out zone %s", goal->x(), goal->y(), zone.c_str());
      return true;
    }
    Path2 path;
    bool ok;
    {
      std::lock_guard<std::mutex> guard(service_mutex_);
      const double tolerance = std::max<double>(req.tolerance, config_.planner.default_tolerance);
      if (tolerance != config_.planner.default_tolerance) {
        core::PlannerParams p = config_.planner;
        p.default_tolerance = tolerance;
        core::GlobalPlanner planner(p);
        ok = plan(planner, *start, *goal, path, why);
      } else {
        ok = plan(*service_planner_, *start, *goal, path, why);
      }
    }
    if (!ok) {
      ROS_WARN("make_plan: no plan from (%.2f, %.2f) to (%.2f, %.2f): %s", start->x(), start->y(), goal->x(), goal->y(), why.c_str());
      return true;
    }
    for (std::size_t i = 0; i < path.size(); ++i) {
      resp.plan.poses.push_back(poseStamped(resp.plan.header, path[i].x(), path[i].y(), i + 1 == path.size() ? goal->z() : 0.0));
    }
    return true;
  }

  bool onClearCostmaps(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
    global_->resetLayers();
    local_->resetLayers();
    ROS_INFO("move_base: costmaps cleared");
    return true;
  }

  // --- the action ------------------------------------------------------------------------------------
  void stop() { cmd_pub_.publish(geometry_msgs::Twist()); }

  /// The keep-out zone (either costmap's filters) at `p` in the global costmap's frame, or "".
  std::string keepoutZoneAt(const Vec3& p) {
    std::string zone = global_->keepoutZoneAt(p.head<2>());
    if (zone.empty() && !framesDiffer()) zone = local_->keepoutZoneAt(p.head<2>());
    return zone;
  }

  std::optional<Vec3> accept(const geometry_msgs::PoseStamped& target) {
    std::string why;
    const auto goal = inFrame(target, global_->config().global_frame, why);
    if (!goal) {
      server_->setAborted(move_base_msgs::MoveBaseResult(),
                         "Aborting on goal because it was sent with an invalid quaternion or frame: " + why);
      ROS_ERROR("move_base: goal rejected: %s", why.c_str());
      return std::nullopt;
    }
    if (const std::string zone = keepoutZoneAt(*goal); !zone.empty()) {
      // A rule of the building, not a failure of move_base: said as a warning, the goal aborted at once.
      const std::string text = fmt("the goal (%.2f, %.2f) lies in keep-out zone ", goal->x(), goal->y()) + zone;
      server_->setAborted(move_base_msgs::MoveBaseResult(), "Aborting on goal because " + text);
      ROS_WARN("move_base: goal rejected: %s", text.c_str());
      return std::nullopt;
    }
    std_msgs::Header header;
    header.frame_id = global_->config().global_frame;
    header.stamp = ros::Time::now();
    goal_pub_.publish(poseStamped(header, goal->x(), goal->y(), goal->z()));
    ROS_INFO("move_base: new goal (%.2f, %.2f, %.2f rad) in %s", goal->x(), goal->y(), goal->z(), header.frame_id.c_str());
    return goal;
  }

  void execute(const move_base_msgs::MoveBaseGoalConstPtr& action_goal) {
    if (config_.shutdown_costmaps) {
      global_->start();
      local_->start();
    }
    auto goal = accept(action_goal->target_pose);
    if (!goal) return;
    reset();
    SimRate rate(config_.controller_frequency);
    while (ros::ok()) {
      if (server_->isPreemptRequested()) {
        if (server_->isNewGoalAvailable()) {
          const auto next = server_->acceptNewGoal();
          goal = accept(next->target_pose);
          if (!goal) {
            stop();
            break;
          }
          reset();
        } else {
          stop();
          controller_->reset();
          server_->setPreempted(move_base_msgs::MoveBaseResult(), "Goal canceled");
          ROS_INFO("move_base: goal canceled; the robot is stopped");
          break;
        }
      }
      if (cycle(*goal)) break;
      rate.sleep();
    }
    if (config_.shutdown_costmaps) {
      global_->stop();
      local_->stop();
    }
    stop();
    if (server_->isActive()) server_->setAborted(move_base_msgs::MoveBaseResult(), "move_base is shutting down");
  }

  void reset() {
    fsm_->reset(ros::Time::now().toSec());
    controller_->reset();
  }

  bool abort(const std::string& text) {
    stop();
    ROS_ERROR("move_base: aborting the goal: %s", text.c_str());
    server_->setAborted(move_base_msgs::MoveBaseResult(), text);
    return true;
  }

  bool framesDiffer() const { return local_->config().global_frame != global_->config().global_frame; }

  /// The node's side of the state machine (core/move_base_fsm.h): tf, costmaps, planners, cmd_vel.
  class Ports : public core::MoveBasePorts {
   public:
    explicit Ports(MoveBase& mb) : mb_(mb) {}
    std::optional<Vec3> robotPose(std::string& why) override {
      const auto pose = mb_.global_->lookupRobotPose();
      if (!pose) why = mb_.global_->tfProblem();
      return pose;
    }
    bool sensorsCurrent(std::string& why) override {
      const auto [current, stale_why] = mb_.local_->isCurrent();
      why = stale_why;
      return current;
    }
    bool makePlan(const Vec3& start, const Vec3& goal, Path2& path, std::string& why) override {
      return mb_.plan(*mb_.planner_, start, goal, path, why, &mb_.plan_lethal_cost_);
    }
    bool planBlocked(const Path2& path, const Vec3& pose) override {
      auto guard = mb_.global_->lock();
      const auto& map = mb_.global_->master();
      return core::planBlocked(map, path, pose.head<2>(), mb_.global_->config().circumscribed_radius + map.resolution(),
                               mb_.plan_lethal_cost_);
    }
    void planMade(const Path2& path, double goal_yaw) override {
      mb_.publishPath({&mb_.plan_pub_, &mb_.generic_plan_pub_}, path, mb_.global_->config().global_frame, goal_yaw);
    }
    void followPlan(const Path2& path, double goal_yaw) override { mb_.controller_->setPlan(mb_.toLocal(path), goal_yaw); }
    core::ControlResult computeVelocity(const Vec3& pose) override {
      // the cycle's pose, unless the local costmap lies in another frame
      const auto local_pose = mb_.framesDiffer() ? mb_.local_->lookupRobotPose() : std::optional<Vec3>(pose);
      core::ControlResult control;
      if (!local_pose) {
        control.why = "tf: " + mb_.local_->tfProblem();
        return control;
      }
      mb_.applySpeedLimit(pose);
      auto guard = mb_.local_->lock();
      return mb_.controller_->compute(mb_.local_->master(), *local_pose, mb_.velocity());
    }
    bool goalReached() override { return mb_.controller_->reached(); }
    void sendVelocity(const Vec3& command) override {
      geometry_msgs::Twist t;
      t.linear.x = command.x();
      t.linear.y = command.y();
      t.angular.z = command.z();
      mb_.cmd_pub_.publish(t);
    }
    void stop() override { mb_.stop(); }
    double runRecovery(const core::RecoveryConfig& r) override {
      mb_.runRecovery(r);
      return ros::Time::now().toSec();
    }
    void feedback(const Vec3& pose) override {
      move_base_msgs::MoveBaseFeedback feedback;
      std_msgs::Header header;
      header.frame_id = mb_.global_->config().global_frame;
      header.stamp = ros::Time::now();
      feedback.base_position = poseStamped(header, pose.x(), pose.y(), pose.z());
      mb_.server_->publishFeedback(feedback);
    }
    void controlled() override { mb_.publishLocal(); }
    void warn(const char* key, const std::string& text, double throttle_s) override {
      if (due(key, throttle_s)) ROS_WARN("move_base: %s", text.c_str());
    }
    void info(const char* key, const std::string& text, double throttle_s) override {
      if (due(key, throttle_s)) ROS_INFO("move_base: %s", text.c_str());
    }

   private:
    bool due(const char* key, double throttle_s) {
      if (throttle_s <= 0) return true;
      const ros::Time now = ros::Time::now();
      ros::Time& last = last_said_[key];
      if (!last.isZero() && now >= last && (now - last).toSec() < throttle_s) return false;
      last = now;
      return true;
    }

    MoveBase& mb_;
    std::map<std::string, ros::Time> last_said_;
  };

  /// Caps the local planner's speed while the footprint at `pose` (global frame) is in a speed
  /// zone of either costmap, saying so once per zone entered and once when it is lifted.
  void applySpeedLimit(const Vec3& pose) {
    auto limit = global_->speedLimitAt(pose);
    if (!framesDiffer()) {
      const auto local = local_->speedLimitAt(pose);
      const double max_vel_x = controller_->params().max_vel_x;
      auto mps = [&](const core::LayeredCostmap::SpeedLimit& l) { return l.percent ? l.value / 100.0 * max_vel_x : l.value; };
      if (local.limited && (!limit.limited || mps(local) < mps(limit))) limit = local;
    }
    const double max_vel_x = controller_->params().max_vel_x;
    const double cap = !limit.limited ? std::numeric_limits<double>::infinity()
                       : limit.percent ? limit.value / 100.0 * max_vel_x : limit.value;
    controller_->setSpeedLimit(cap);
    const std::string zone = limit.limited ? limit.zone : "";
    if (zone == speed_zone_) return;
    speed_zone_ = zone;
    if (zone.empty()) {
      ROS_INFO("move_base: out of the speed zone: max_vel_x %.2f m/s again", max_vel_x);
    } else {
      const double effective = std::max(std::min(cap, max_vel_x), controller_->params().min_vel_x);
      ROS_INFO("move_base: in speed zone %s: at most %.2f m/s%s", zone.c_str(), effective,
               limit.percent ? fmt(" (%.0f%% of max_vel_x %.2f m/s)", limit.value, max_vel_x).c_str() : "");
    }
  }

  /// One control cycle; true when the goal is finished (succeeded or aborted).
  bool cycle(const Vec3& goal) {
    if (server_reset_pending_) {
      // reset_simulation (or a bag played again): the pose, plan and obstacles of before no longer
      // hold. watchClock() clears the costmaps and restarts the server once this goal has ended.
      return abort(fmt("the clock went back by %.1f s (the simulation was reset?); the costmaps are cleared, send the "
                       "goal again", clock_jump_s_.load()));
    }
    switch (fsm_->cycle(ros::Time::now().toSec(), goal, ports_)) {
      case core::GoalOutcome::kSucceeded:
        controller_->reset();
        server_->setSucceeded(move_base_msgs::MoveBaseResult(), "Goal reached.");
        ROS_INFO("move_base: goal reached");
        return true;
      case core::GoalOutcome::kAborted:
        return abort(fsm_->abortText());
      case core::GoalOutcome::kActive:
        break;
    }
    return false;
  }

  /// The global plan in the local costmap's frame.
  Path2 toLocal(const Path2& path) {
    if (!framesDiffer()) return path;
    const std::string src = global_->config().global_frame, dst = local_->config().global_frame;
    geometry_msgs::TransformStamped t;
    try {
      t = tf_.lookupTransform(dst, src, ros::Time(0), ros::Duration(0.2));
    } catch (const tf2::TransformException& e) {
      ROS_WARN("move_base: cannot transform the plan from %s to %s: %s", src.c_str(), dst.c_str(), e.what());
      return {};
    }
    const Vec3 base(t.transform.translation.x, t.transform.translation.y, tf2::getYaw(t.transform.rotation));
    Path2 out;
    for (const auto& p : path) out.push_back(compose(base, Vec3(p.x(), p.y(), 0.0)).head<2>());
    return out;
  }

  void publishLocal() {
    const std::string frame = local_->config().global_frame;
    if (local_plan_pub_.getNumSubscribers() && !controller_->lastTrajectory().empty()) {
      Path2 path;
      for (const auto& p : controller_->lastTrajectory()) path.push_back(p.head<2>());
      publishPath({&local_plan_pub_}, path, frame);
    }
    if (local_global_plan_pub_.getNumSubscribers()) publishPath({&local_global_plan_pub_}, controller_->plan(), frame);
  }

  // --- recoveries --------------------------------------------------------------------------------------
  void runRecovery(const core::RecoveryConfig& r) {
    if (r.kind == core::RecoveryKind::kClearCostmap) {
      std::vector<ros_glue::CostmapROS*> maps;
      if (r.affected_maps != "local") maps.push_back(global_.get());
      if (r.affected_maps != "global") maps.push_back(local_.get());
      for (auto* cm : maps) {
        const auto pose = cm->lookupRobotPose();
        if (!pose) continue;
        if (r.invert_area_to_clear) {
          ROS_WARN("clear_costmap_recovery: invert_area_to_clear clears everything here");
          cm->resetLayers();
        } else {
          cm->resetLayers(Vec3(pose->x(), pose->y(), r.reset_distance));
        }
        if (r.force_updating) cm->update();
      }
    } else if (r.kind == core::RecoveryKind::kRotate) {
      rotateRecovery(r);
    } else {
      backUpRecovery(r);
    }
  }

  bool footprintFree(const Vec3& pose) {
    auto guard = local_->lock();
    return core::footprintCost(local_->master(), pose, local_->config().footprint, true) >= 0;
  }

  /// rotate_recovery: one full turn in place, stopping before a collision.
  void rotateRecovery(const core::RecoveryConfig& cfg) {
    const auto& p = config_.local;
    const double max_vel = config_.local_ros.max_rotational_vel, min_vel = p.min_in_place_vel_theta;
    SimRate rate(cfg.frequency);
    const auto start = local_->lookupRobotPose();
    if (!start) return;
    double turned = 0.0, last_yaw = start->z();
    const double tolerance = 0.1;
    while (ros::ok() && !server_->isPreemptRequested()) {
      const auto pose = local_->lookupRobotPose();
      if (!pose) break;
      turned += std::abs(std::remainder(pose->z() - last_yaw, 2 * M_PI));
      last_yaw = pose->z();
      const double left = 2 * M_PI - turned;
      if (left <= tolerance) break;
      for (double sim = 0.0; sim < left; sim += cfg.sim_granularity) {  // the footprint along the rest of the turn
        if (!footprintFree(Vec3(pose->x(), pose->y(), pose->z() + sim))) {
          ROS_WARN("rotate_recovery: cannot rotate in place, a collision is %.2f rad ahead", sim);
          stop();
          return;
        }
      }
      geometry_msgs::Twist t;
      t.angular.z = std::min(std::max(std::sqrt(2 * p.acc_lim_theta * left), min_vel), max_vel);
      cmd_pub_.publish(t);
      rate.sleep();
    }
    stop();
  }

  /// Backs straight up by back_up_distance at back_up_speed while the footprint stays clear.
  void backUpRecovery(const core::RecoveryConfig& cfg) {
    SimRate rate(cfg.frequency);
    const auto start = local_->lookupRobotPose();
    if (!start) return;
    while (ros::ok() && !server_->isPreemptRequested()) {
      const auto pose = local_->lookupRobotPose();
      if (!pose) break;
      const double moved = (pose->head<2>() - start->head<2>()).norm();
      if (moved >= cfg.distance) break;
      const double step = 0.05;
      if (!footprintFree(Vec3(pose->x() - step * std::cos(pose->z()), pose->y() - step * std::sin(pose->z()), pose->z()))) {
        ROS_WARN("back_up recovery: an obstacle behind the robot; stopped after %.2f m", moved);
        break;
      }
      geometry_msgs::Twist t;
      t.linear.x = -cfg.speed;
      cmd_pub_.publish(t);
      rate.sleep();
    }
    stop();
  }

  ros::NodeHandle nh_;
  tf2_ros::Buffer tf_;
  tf2_ros::TransformListener listener_;
  using Server = actionlib::SimpleActionServer<move_base_msgs::MoveBaseAction>;
  std::unique_ptr<Server> makeServer() {
    return std::make_unique<Server>(nh_, "move_base", [this](const move_base_msgs::MoveBaseGoalConstPtr& g) {
      executing_ = true;
      execute(g);
      executing_ = false;
    }, false);
  }

  /// After the clock goes back (reset_simulation), actionlib's server would refuse every new goal:
  /// their stamps are older than its last one ("canceled because another goal was recieved"). It
  /// is started afresh once no goal runs (an active one is aborted by cycle()), and the costmaps
  /// are cleared. The one place that watches the clock; cycle() reads server_reset_pending_.
  void watchClock() {
    const ros::Time now = ros::Time::now();
    if (!clock_seen_.isZero() && now + ros::Duration(1.0) < clock_seen_) {
      clock_jump_s_ = (clock_seen_ - now).toSec();
      server_reset_pending_ = true;
      // tf2_ros's listener clears its buffer only if a tf message arrives after it has seen the
      // clock go back; one handled first is refused as old data and the newest transform stays
      // hundreds of seconds ahead ("extrapolation ... only time 398.18 is in the buffer").
      // Static transforms survive a clear.
      tf_.clear();
    } else if (!clock_seen_.isZero()) {
      // A tf message stamped before the jump can still be handled after that clear (seen on a busy
      // machine: "only time 491.04 is in the buffer" at 52 s, the robot pose unavailable for
      // controller_patience). tf2 then refuses every newer message as older than its cache, until
      // the clock catches up. So no transform between the robot and the global frame may be ahead
      // of the clock: each is checked on its own (one stale link, map -> odom, makes the whole
      // chain's lookup fail as extrapolation, and would hide it).
      const auto& c = global_->config();
      std::string child = c.robot_base_frame, parent;
      for (int depth = 0; depth < 16 && child != c.global_frame && tf_._getParent(child, ros::Time(0), parent); ++depth) {
        ros::Time newest;
        try {
          newest = tf_.lookupTransform(parent, child, ros::Time(0)).header.stamp;
        } catch (const tf2::TransformException&) {
          break;  // no transform yet: nothing ahead of the clock
        }
        if (newest > now + ros::Duration(1.0)) {
          ROS_WARN("move_base: tf holds %s -> %s at %.2f s, ahead of the clock (%.2f s): a message from before the "
                   "clock went back; the tf buffer is cleared again", child.c_str(), parent.c_str(), newest.toSec(),
                   now.toSec());
          tf_.clear();
          break;
        }
        child = parent;
      }
    }
    clock_seen_ = now;
    if (!server_reset_pending_ || executing_) return;
    server_reset_pending_ = false;
    server_.reset();
    server_ = makeServer();
    server_->start();
    global_->resetLayers();
    local_->resetLayers();
    ROS_WARN("move_base: the clock went back (the simulation was reset?): the costmaps are cleared and the action "
             "server started afresh, so goals sent from now on are taken");
  }

  std::unique_ptr<Server> server_;
  ros::SteadyTimer clock_watch_;
  ros::Time clock_seen_;
  std::atomic<bool> executing_{false}, server_reset_pending_{false};
  std::atomic<double> clock_jump_s_{0.0};  // [s] how far the clock went back, for the abort text
  std::unique_ptr<ros_glue::CostmapROS> global_, local_;
  core::MoveBaseConfig config_;
  std::unique_ptr<core::GlobalPlanner> planner_, service_planner_;
  bool auto_lethal_cost_ = true;
  int plan_lethal_cost_ = core::cost::kInscribed;  // the lethal_cost the followed plan was made with
  /// The global planner's lethal_cost (the global costmap's lock held).
  int lethalCost() const { return auto_lethal_cost_ ? global_->contactCost() : config_.planner.lethal_cost; }
  std::unique_ptr<core::TrajectoryController> controller_;
  std::string speed_zone_;  // the speed zone the robot is in ("" none), for saying so once
  std::mutex velocity_mutex_, service_mutex_;
  Vec3 velocity_ = Vec3::Zero();
  ros::Publisher cmd_pub_, plan_pub_, generic_plan_pub_, local_plan_pub_, local_global_plan_pub_, goal_pub_, action_goal_pub_,
      heartbeat_pub_;
  ros::Subscriber odom_sub_, simple_goal_sub_;
  ros::ServiceServer make_plan_srv_, clear_srv_;
  // The goal's state machine (the action thread only).
  std::unique_ptr<core::MoveBaseStateMachine> fsm_;
  Ports ports_{*this};
};

}  // namespace
}  // namespace mbot

int main(int argc, char** argv) {
  ros::init(argc, argv, "move_base");
  // Scans wait for their transform, the action runs in actionlib's thread: several callback threads
  // keep the costmaps updating meanwhile.
  ros::AsyncSpinner spinner(4);
  std::unique_ptr<mbot::MoveBase> move_base;
  try {
    move_base = std::make_unique<mbot::MoveBase>();
  } catch (const mbot::core::ParamError& e) {
    ROS_FATAL("move_base: %s", e.what());
    return 1;
  }
  spinner.start();
  ros::waitForShutdown();
  return 0;
}
