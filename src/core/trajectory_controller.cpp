#include "mbot_slam_navigation/core/trajectory_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace mbot {
namespace core {
namespace {
constexpr double kStoppedTrans = 1e-2;  // [m/s] ROS's trans_stopped_velocity
constexpr double kStoppedRot = 1e-2;    // [rad/s] rot_stopped_velocity
// [m] A new plan whose first kNewWayAlong_m strays farther than kNewWayOff_m from the old one
// takes another way.
constexpr double kNewWayAlong_m = 1.0, kNewWayOff_m = 0.2;
double sign(double v) { return v >= 0.0 ? 1.0 : -1.0; }

/// Whether `next` starts another way than `prev` (an empty `prev` included).
bool anotherWay(const std::vector<Eigen::Vector2d>& prev, const std::vector<Eigen::Vector2d>& next) {
  if (prev.empty() || next.empty()) return !next.empty();
  double along = 0.0;
  for (std::size_t i = 0; i < next.size() && along <= kNewWayAlong_m; ++i) {
    if (i > 0) along += (next[i] - next[i - 1]).norm();
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& q : prev) nearest = std::min(nearest, (q - next[i]).squaredNorm());
    if (nearest > kNewWayOff_m * kNewWayOff_m) return true;
  }
  return false;
}
double normalizeAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }
std::string g(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
}  // namespace

void readLocalPlannerParams(const ParamValue& values, const std::string& ns, const Warn& warn_or_empty, double controller_frequency,
                            LocalPlannerParams& p, LocalPlannerRosParams& ros) {
  const Warn warn = orIgnore(warn_or_empty);
  ParamReader r(values, ns, warn);
  p = LocalPlannerParams();
  ros = LocalPlannerRosParams();
  p.acc_lim_x = r.number("acc_lim_x", p.acc_lim_x, "[m/s^2] forward acceleration limit", 0.0);
  p.acc_lim_y = r.number("acc_lim_y", p.acc_lim_y, "[m/s^2] sideways acceleration limit (holonomic robots)", 0.0);
  p.acc_lim_theta = r.deprecated("acc_lim_theta", "acc_lim_th", p.acc_lim_theta, "[rad/s^2] rotational acceleration limit");
  for (const char* wrong : {"acc_limit_x", "acc_limit_y", "acc_limit_th"}) {
    if (!r.has(wrong)) continue;
    r.markRead(wrong);
    std::string right = wrong;
    right.replace(0, 9, "acc_lim");
    warn("parameter " + r.where(wrong) + " is not read; the name is " + right + " (the old documentation was wrong)");
  }
  p.max_vel_x = r.number("max_vel_x", p.max_vel_x, "[m/s] fastest forward speed", 0.0);
  p.min_vel_x = r.number("min_vel_x", p.min_vel_x, "[m/s] slowest forward speed sampled", 0.0);
  if (r.has("max_rotational_vel")) {
    // ROS reads it at start-up, then dynamic_reconfigure overwrites it with max/min_vel_theta.
    warn("parameter " + r.where("max_rotational_vel") +
         " has no effect in TrajectoryPlannerROS (dynamic_reconfigure replaces it with max_vel_theta / min_vel_theta); "
         "rotate_recovery still reads it");
  }
  ros.max_rotational_vel = r.number("max_rotational_vel", ros.max_rotational_vel,
                                    "[rad/s] fastest turn of rotate_recovery (the planner uses max_vel_theta)");
  p.max_vel_theta = r.number("max_vel_theta", p.max_vel_theta, "[rad/s] fastest counter-clockwise turn", 0.0);
  p.min_vel_theta = r.number("min_vel_theta", p.min_vel_theta, "[rad/s] fastest clockwise turn (<= 0)");
  if (p.min_vel_theta > 0) {
    throw ParamError("parameter " + r.where("min_vel_theta") + " must be <= 0 (it is the fastest clockwise turn), got " +
                     g(p.min_vel_theta));
  }
  p.min_in_place_vel_theta = r.deprecated("min_in_place_vel_theta", "min_in_place_rotational_vel", p.min_in_place_vel_theta,
                                          "[rad/s] slowest turn on the spot");
  double backup = p.escape_vel;
  if (r.has("backup_vel")) {
    warn("parameter " + r.where("backup_vel") + " is deprecated; use escape_vel");
    backup = r.number("backup_vel", backup, "[m/s] deprecated name of escape_vel");
  }
  p.escape_vel = r.number("escape_vel", backup, "[m/s] speed when backing out of a dead end (< 0: backwards)");
  if (p.escape_vel >= 0) {
    warn("parameter " + r.where("escape_vel") + " is " + g(p.escape_vel) +
         ": a non-negative escape velocity moves the robot forward when it should back up");
  }
  p.sim_time = r.number("sim_time", p.sim_time, "[s] how far ahead each sampled trajectory is simulated", std::nullopt, true);
  p.sim_granularity = r.number("sim_granularity", p.sim_granularity, "[m] step between collision checks along a trajectory",
                               std::nullopt, true);
  p.angular_sim_granularity = r.number("angular_sim_granularity", p.angular_sim_granularity,
                                       "[rad] rotational step between collision checks", std::nullopt, true);
  p.vx_samples = static_cast<int>(r.integer("vx_samples", p.vx_samples, "forward speeds sampled"));
  p.vtheta_samples = static_cast<int>(r.integer("vtheta_samples", p.vtheta_samples, "turn rates sampled"));
  for (auto [key, value] : {std::make_pair("vx_samples", &p.vx_samples), std::make_pair("vtheta_samples", &p.vtheta_samples)}) {
    if (*value < 1) {
      warn("parameter " + r.where(key) + " is " + std::to_string(*value) + "; at least one sample is taken");
      *value = 1;
    }
  }
  p.path_distance_bias = r.deprecated("path_distance_bias", "pdist_scale", p.path_distance_bias,
                                      "weight of staying near the global path");
  p.goal_distance_bias = r.deprecated("goal_distance_bias", "gdist_scale", p.goal_distance_bias,
                                      "weight of getting nearer to the local goal");
  p.occdist_scale = r.number("occdist_scale", p.occdist_scale, "weight of keeping away from obstacles (the highest cost met)",
                             0.0);
  if (!r.has("meter_scoring")) {
    warn("parameter " + r.where("meter_scoring") +
         " is not set: the distance biases count cells, so the behaviour changes with the costmap resolution; set it to true");
  }
  p.meter_scoring = r.boolean("meter_scoring", p.meter_scoring,
                              "distances in the cost in metres (true) or cells (false, ROS's default)");
  p.heading_lookahead = r.number("heading_lookahead", p.heading_lookahead, "[m] how far ahead in-place turns are scored",
                                 0.0);
  p.heading_scoring = r.boolean("heading_scoring", p.heading_scoring, "score the heading to the path instead of distance");
  p.heading_scoring_timestep = r.number("heading_scoring_timestep", p.heading_scoring_timestep,
                                        "[s] how far along a trajectory its heading is scored", 0.0);
  p.oscillation_reset_dist = r.number("oscillation_reset_dist", p.oscillation_reset_dist,
                                      "[m] travel that clears the oscillation flags", 0.0);
  p.escape_reset_dist = r.number("escape_reset_dist", p.escape_reset_dist, "[m] travel that ends escaping", 0.0);
  p.escape_reset_theta = r.number("escape_reset_theta", p.escape_reset_theta, "[rad] turn that ends escaping", 0.0);
  p.holonomic_robot = r.boolean("holonomic_robot", p.holonomic_robot, "sample sideways speeds (y_vels) too");
  p.dwa = r.boolean("dwa", p.dwa, "sample only speeds reachable within one control period (Dynamic Window)");
  p.simple_attractor = r.boolean("simple_attractor", p.simple_attractor,
                                 "score by straight-line distance to the goal instead of the path grids");
  const ParamValue y_vels = r.raw("y_vels", ParamValue::ofString("-0.3,-0.1,0.1,-0.3"),
                                  "[m/s] sideways speeds sampled by a holonomic robot (list, or a comma-separated string)",
                                  "list");
  p.y_vels.clear();
  bool ok = true;
  if (y_vels.type == ParamValue::Type::kString) {
    std::string text = y_vels.s;
    std::replace(text.begin(), text.end(), ',', ' ');
    std::istringstream in(text);
    double v;
    while (in >> v) p.y_vels.push_back(v);
    ok = in.eof();
  } else if (y_vels.type == ParamValue::Type::kList) {
    for (const auto& v : y_vels.items) {
      if (!v.isNumber()) ok = false;
      else p.y_vels.push_back(v.number());
    }
  } else {
    ok = false;
  }
  if (!ok) throw ParamError("parameter " + r.where("y_vels") + " must be a list of speeds, got " + y_vels.repr());
  double frequency = r.has("controller_frequency")
                         ? r.number("controller_frequency", controller_frequency,
                                    "[Hz] the control rate the planner assumes (default: move_base's controller_frequency)")
                         : controller_frequency;
  if (frequency <= 0) {
    warn("controller_frequency " + g(frequency) + " is not positive; the planner assumes 20 Hz");
    frequency = 20.0;
  }
  p.sim_period = 1.0 / frequency;
  ros.xy_goal_tolerance = r.number("xy_goal_tolerance", ros.xy_goal_tolerance, "[m] how near the goal counts as reached", 0.0);
  ros.yaw_goal_tolerance = r.number("yaw_goal_tolerance", ros.yaw_goal_tolerance,
                                    "[rad] how near the goal's heading counts as reached", 0.0);
  ros.latch_xy_goal_tolerance = r.boolean("latch_xy_goal_tolerance", ros.latch_xy_goal_tolerance,
                                          "once within xy_goal_tolerance, only turn in place to the goal's heading");
  ros.prune_plan = r.boolean("prune_plan", ros.prune_plan, "drop the plan's points the robot has passed");
  ros.stop_time_buffer = r.number("stop_time_buffer", ros.stop_time_buffer,
                                  "[s] ROS's margin before a collision; read, not used by this planner", 0.0);
  for (const char* key : {"world_model", "restore_defaults", "point_grid", "x_goal_tolerance", "y_goal_tolerance"}) {
    r.ignored(key, "accepted as in ROS, where it has no effect or is superseded");
  }
  r.reportUnknown();
}

std::vector<Eigen::Vector2d> prunePlan(const std::vector<Eigen::Vector2d>& plan, const Eigen::Vector3d& pose) {
  for (std::size_t i = 0; i < plan.size(); ++i) {
    if ((plan[i] - pose.head<2>()).squaredNorm() < 1.0) return {plan.begin() + static_cast<long>(i), plan.end()};
  }
  return plan;
}

TrajectoryController::TrajectoryController(const LocalPlannerParams& params, const LocalPlannerRosParams& ros,
                                           const Footprint& footprint)
    : planner_(params, footprint), ros_(ros) {}

void TrajectoryController::setPlan(const std::vector<Eigen::Vector2d>& plan, double goal_yaw) {
  // A new plan ends escape mode: the plan was made on what the robot saw after it backed out, and
  // it passes where the robot fits (lethal_cost). Kept, the escape allowed only turning on the
  // spot until a quarter turn, and the turning side then forbade turning back: in clutter, a full
  // circle before the robot could follow the plan (ROS keeps it). A plan along another way (an
  // obstacle found on the old one) also clears the sides the robot turned to without moving: they
  // were learnt on the old way.
  if (anotherWay(plan_, plan)) planner_.resetOscillation();
  else planner_.resetEscape();
  plan_ = plan;
  goal_yaw_ = goal_yaw;
  reached_ = false;
  latched_ = false;
}

void TrajectoryController::reset() {
  planner_.resetOscillation();
  rotating_to_goal_ = false;
  reached_ = false;
  latched_ = false;
}

bool TrajectoryController::safe(const Costmap& costmap, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel,
                                const Eigen::Vector3d& cmd) {
  return planner_.scoreTrajectory(costmap, pose, vel, cmd) >= 0;
}

ControlResult TrajectoryController::compute(const Costmap& costmap, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel) {
  const LocalPlannerParams& p = planner_.params();
  ControlResult out;
  out.standing = std::abs(vel.x()) < kStandingTrans && std::abs(vel.y()) < kStandingTrans && std::abs(vel.z()) < kStandingRot;
  last_trajectory_.clear();
  if (plan_.empty()) {
    out.why = "no global plan";
    return out;
  }
  if (ros_.prune_plan) plan_ = prunePlan(plan_, pose);
  planner_.setPlan(plan_);
  const Eigen::Vector2d goal = plan_.back();
  if (latched_ || (goal - pose.head<2>()).norm() <= ros_.xy_goal_tolerance) {
    if (ros_.latch_xy_goal_tolerance) latched_ = true;
    const double diff = normalizeAngle(goal_yaw_ - pose.z());
    if (std::abs(diff) <= ros_.yaw_goal_tolerance) {
      rotating_to_goal_ = false;
      latched_ = false;
      reached_ = true;
      out.valid = true;
      return out;
    }
    planner_.updateGrids(costmap, pose);
    const bool moving = std::abs(vel.x()) > kStoppedTrans || std::abs(vel.y()) > kStoppedTrans || std::abs(vel.z()) > kStoppedRot;
    if (moving && !rotating_to_goal_) {
      // Slow down with the acceleration limits over one control period.
      const Eigen::Vector3d cmd(sign(vel.x()) * std::max(0.0, std::abs(vel.x()) - p.acc_lim_x * p.sim_period),
                                sign(vel.y()) * std::max(0.0, std::abs(vel.y()) - p.acc_lim_y * p.sim_period),
                                sign(vel.z()) * std::max(0.0, std::abs(vel.z()) - p.acc_lim_theta * p.sim_period));
      if (safe(costmap, pose, vel, cmd)) {
        out.valid = true;
        out.command = cmd;
      } else {
        out.why = "cannot slow down safely at the goal";
      }
      return out;
    }
    rotating_to_goal_ = true;
    double vth = diff > 0 ? std::min(p.max_vel_theta, std::max(p.min_in_place_vel_theta, diff))
                          : std::max(p.min_vel_theta, std::min(-p.min_in_place_vel_theta, diff));
    const double fastest = std::abs(vel.z()) + p.acc_lim_theta * p.sim_period;
    const double slowest = std::abs(vel.z()) - p.acc_lim_theta * p.sim_period;
    vth = sign(vth) * std::min(std::max(std::abs(vth), slowest), fastest);
    vth = sign(vth) * std::min(std::sqrt(2 * p.acc_lim_theta * std::abs(diff)), std::abs(vth));  // stop on the yaw
    vth = vth > 0 ? std::min(p.max_vel_theta, std::max(p.min_in_place_vel_theta, vth))
                  : std::max(p.min_vel_theta, std::min(-p.min_in_place_vel_theta, vth));
    const Eigen::Vector3d cmd(0.0, 0.0, vth);
    if (safe(costmap, pose, vel, cmd)) {
      out.valid = true;
      out.command = cmd;
    } else {
      out.why = "cannot turn to the goal orientation without a collision";
    }
    return out;
  }
  rotating_to_goal_ = false;
  const Trajectory best = planner_.findBestPath(costmap, pose, vel);
  out.footprint_scale = planner_.lastFootprintScale();
  // Said only for a lethal cell deeper than one cell inside the outline: nearer the outline it is
  // the grid's rounding of a surface the robot has come up to (a cell holds a surface point
  // anywhere in it), which happens beside obstacles in clutter; the rule on the distance applies
  // either way.
  const double inside = planner_.lastObstacleInside();
  if (inside < inscribedRadius(planner_.footprint()) - costmap.resolution()) out.obstacle_inside_m = inside;
  out.touching = out.footprint_scale < 1.0 || std::isfinite(inside);
  last_trajectory_ = best.points;
  if (best.cost < 0) {
    out.why = "no valid trajectory (every sampled command collides or leaves the plan)";
    return out;
  }
  out.valid = true;
  out.command = Eigen::Vector3d(best.xv, best.yv, best.thetav);
  return out;
}

}  // namespace core
}  // namespace mbot
