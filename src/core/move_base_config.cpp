#include "mbot_slam_navigation/core/move_base_config.h"

#include <map>
#include <set>
#include <tuple>
#include <algorithm>
#include <cmath>

namespace mbot {
namespace core {
namespace {
const std::map<std::string, std::string> kGlobalPlanners = {{"navfn/NavfnROS", "NavfnROS"},
                                                            {"global_planner/GlobalPlanner", "GlobalPlanner"}};
const std::map<std::string, std::string> kLocalPlanners = {{"base_local_planner/TrajectoryPlannerROS", "TrajectoryPlannerROS"},
                                                           {"dwa_local_planner/DWAPlannerROS", "DWAPlannerROS"}};
const std::vector<std::string> kRecoveryTypes = {"clear_costmap_recovery/ClearCostmapRecovery", "rotate_recovery/RotateRecovery",
                                                 "mbot_slam_navigation/BackUpRecovery", "moveback_recovery/MoveBackRecovery"};

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}
std::vector<std::string> keysOf(const std::map<std::string, std::string>& m) {
  std::vector<std::string> out;
  for (const auto& [k, _] : m) out.push_back(k);
  return out;
}
const char* const kRecoveriesDoc =
    "the recoveries in order, [{name: ..., type: ...}, ...]; default: conservative_reset, rotate_recovery, back_up, "
    "aggressive_reset, rotate_recovery";

RecoveryKind kindOf(const std::string& type) {
  if (type == kRecoveryTypes[0]) return RecoveryKind::kClearCostmap;
  if (type == kRecoveryTypes[1]) return RecoveryKind::kRotate;
  return RecoveryKind::kBackUp;
}
}  // namespace

MoveBaseConfig readMoveBaseConfig(const ParamValue& values, const std::string& ns, const Warn& warn_or_empty,
                                  double circumscribed_radius) {
  const Warn warn = orIgnore(warn_or_empty);
  MoveBaseConfig c;
  ParamReader r(values, ns, warn);
  c.controller_frequency = r.number("controller_frequency", c.controller_frequency,
                                    "[Hz] how often the local planner runs and velocity commands are sent", std::nullopt, true);
  c.planner_frequency = r.number("planner_frequency", c.planner_frequency,
                                 "[Hz] how often the global plan is made again (0: on a new goal and when the local planner fails)",
                                 0.0);
  c.controller_patience = r.number("controller_patience", c.controller_patience,
                                   "[s] how long without a valid velocity command before the recoveries run", 0.0);
  c.planner_patience = r.number("planner_patience", c.planner_patience,
                                "[s] how long without a valid plan before the recoveries run", 0.0);
  c.max_planning_retries = r.integer("max_planning_retries", c.max_planning_retries,
                                     "planning failures before the recoveries run (-1: planner_patience decides)");
  c.oscillation_timeout = r.number("oscillation_timeout", c.oscillation_timeout,
                                   "[s] how long without moving oscillation_distance before the recoveries run (0: never; "
                                   "ROS's default 0)",
                                   0.0);
  c.oscillation_distance = r.number("oscillation_distance", c.oscillation_distance,
                                    "[m] travel that resets the oscillation timer", 0.0);
  c.progress_timeout = r.number("progress_timeout", c.progress_timeout,
                                "[s] ours: how long without the path to the goal getting 0.25 m shorter before the recoveries "
                                "run, and after the last, the goal is aborted (0: never)",
                                0.0);
  c.standing_touch_wait = r.number("standing_touch_wait", c.standing_touch_wait,
                                   "[s] ours: when something comes up to the standing robot and touches its footprint (a "
                                   "person walking past), the robot stands this long, or until it is clear, before moving out "
                                   "(0: at once)",
                                   0.0);
  c.recovery_behavior_enabled = r.boolean("recovery_behavior_enabled", c.recovery_behavior_enabled,
                                          "run the recovery behaviours when stuck (else abort at once)");
  c.clearing_rotation_allowed = r.boolean("clearing_rotation_allowed", c.clearing_rotation_allowed,
                                          "the default recoveries include turning on the spot");
  c.shutdown_costmaps = r.boolean("shutdown_costmaps", c.shutdown_costmaps, "stop the costmaps while there is no goal");
  c.conservative_reset_dist = r.number("conservative_reset_dist", c.conservative_reset_dist,
                                       "[m] the default conservative_reset keeps obstacles within this square around the robot",
                                       0.0);
  c.make_plan_clear_costmap = r.boolean("make_plan_clear_costmap", c.make_plan_clear_costmap,
                                        "the make_plan service clears the costmap around the robot first");
  c.make_plan_add_unreachable_goal = r.boolean("make_plan_add_unreachable_goal", c.make_plan_add_unreachable_goal,
                                               "make_plan appends the goal to a plan that ends short of it");
  c.global_type = r.string("base_global_planner", c.global_type,
                           "the global planner: navfn/NavfnROS or global_planner/GlobalPlanner");
  c.local_type = r.string("base_local_planner", c.local_type,
                          "the local planner: base_local_planner/TrajectoryPlannerROS or dwa_local_planner/DWAPlannerROS "
                          "(served by TrajectoryPlannerROS with dwa: true)");
  for (const auto& [key, value, known] : {std::make_tuple("base_global_planner", c.global_type, &kGlobalPlanners),
                                          std::make_tuple("base_local_planner", c.local_type, &kLocalPlanners)}) {
    if (known->count(value)) continue;
    const std::string guess = nearestKey(value, keysOf(*known));
    throw ParamError("parameter " + r.where(key) + ": unknown planner \"" + value + "\"" +
                     (guess.empty() ? "" : " (did you mean " + guess + "?)") + "; this move_base provides " + joined(keysOf(*known)));
  }
  c.global_ns = kGlobalPlanners.at(c.global_type);
  c.local_ns = kLocalPlanners.at(c.local_type);

  // Global planner: navfn's keys (NavfnROS) or global_planner's (GlobalPlanner: use_dijkstra).
  const ParamValue* gv = r.values().get(c.global_ns);
  ParamReader g(gv ? *gv : ParamValue::ofMap(), r.where(c.global_ns), warn);
  c.planner.use_astar = c.global_ns == "GlobalPlanner"
                            ? !g.boolean("use_dijkstra", !c.planner.use_astar, "GlobalPlanner: Dijkstra (true) or A* (false)")
                            : g.boolean("use_astar", c.planner.use_astar, "ours: A* instead of navfn's Dijkstra");
  c.planner.allow_unknown = g.boolean("allow_unknown", c.planner.allow_unknown, "plans may cross unknown cells");
  c.planner.default_tolerance = g.number("default_tolerance", c.planner.default_tolerance,
                                         "[m] plan to the nearest free cell within this of a blocked goal", 0.0);
  c.planner.lethal_cost = static_cast<int>(
      g.integer("lethal_cost", 0,
                "cells at this cost or above are obstacles to the plan (global_planner's key, 1..253); 0: the global "
                "costmap's contact cost, below which the robot's footprint stays clear of lethal cells (253 when its "
                "inflation cannot tell), so that the local planner can follow every plan",
                0));
  if (c.planner.lethal_cost > cost::kInscribed) {
    throw ParamError("parameter " + g.where("lethal_cost") + " must be in 0..253, got " + std::to_string(c.planner.lethal_cost));
  }
  for (const char* key : {"visualize_potential", "planner_window_x", "planner_window_y", "planner_costmap_publish_frequency",
                          "use_quadratic", "use_grid_path", "old_navfn_behavior", "neutral_cost", "cost_factor",
                          "publish_potential", "orientation_mode", "orientation_window_size", "outline_map"}) {
    g.ignored(key, "a key of navfn or global_planner that this planner does not need");
  }
  g.reportUnknown();

  // Local planner.
  if (c.local_ns == "DWAPlannerROS") {
    warn(r.where("base_local_planner") +
         ": DWAPlannerROS is served by TrajectoryPlannerROS with dwa: true, reading the DWAPlannerROS namespace");
  }
  const ParamValue* lv = r.values().get(c.local_ns);
  ParamValue local = lv && lv->type == ParamValue::Type::kMap ? *lv : ParamValue::ofMap();
  if (c.local_ns == "DWAPlannerROS" && !local.get("dwa")) local.fields["dwa"] = ParamValue::ofBool(true);
  readLocalPlannerParams(local, r.where(c.local_ns), warn, c.controller_frequency, c.local, c.local_ros);

  // Recoveries.
  std::vector<RecoveryConfig> out;
  if (r.has("recovery_behaviors")) {
    const ParamValue spec = r.raw("recovery_behaviors", ParamValue::ofList(), kRecoveriesDoc, "list");
    bool ok = spec.type == ParamValue::Type::kList;
    for (const auto& b : spec.items) {
      const ParamValue* n = b.get("name");
      const ParamValue* t = b.get("type");
      ok = ok && n && t && n->type == ParamValue::Type::kString && t->type == ParamValue::Type::kString;
    }
    if (!ok) {
      throw ParamError("parameter " + r.where("recovery_behaviors") + " must be a list of {name: ..., type: ...}, got " + spec.repr());
    }
    for (const auto& b : spec.items) {
      RecoveryConfig rc;
      rc.name = b.get("name")->s;
      rc.type = b.get("type")->s;
      if (std::find(kRecoveryTypes.begin(), kRecoveryTypes.end(), rc.type) == kRecoveryTypes.end()) {
        const std::string guess = nearestKey(rc.type, kRecoveryTypes);
        throw ParamError("parameter " + r.where("recovery_behaviors") + ": unknown recovery type \"" + rc.type + "\"" +
                         (guess.empty() ? "" : " (did you mean " + guess + "?)") + "; known: " + joined(kRecoveryTypes));
      }
      out.push_back(rc);
    }
  } else {
    r.raw("recovery_behaviors", ParamValue::ofList(), kRecoveriesDoc, "list");
    const std::vector<std::pair<std::string, int>> defaults = {
        {"conservative_reset", 0}, {"rotate_recovery", 1}, {"back_up", 2}, {"aggressive_reset", 0}, {"rotate_recovery", 1}};
    for (const auto& [name, type] : defaults) {
      RecoveryConfig rc;
      rc.name = name;
      rc.type = kRecoveryTypes[type];
      out.push_back(rc);
    }
  }
  if (!c.clearing_rotation_allowed) {
    out.erase(std::remove_if(out.begin(), out.end(), [](const RecoveryConfig& b) { return b.type == kRecoveryTypes[1]; }), out.end());
  }
  std::set<std::string> skip = {"global_costmap", "local_costmap", c.global_ns, c.local_ns};
  for (auto& rc : out) {
    skip.insert(rc.name);
    rc.kind = kindOf(rc.type);
    const ParamValue* pv = r.values().get(rc.name);
    ParamReader pr(pv && pv->type == ParamValue::Type::kMap ? *pv : ParamValue::ofMap(), r.where(rc.name), warn);
    if (rc.kind == RecoveryKind::kClearCostmap) {
      const double fallback = rc.name == "conservative_reset" && !r.has("recovery_behaviors") ? c.conservative_reset_dist
                              : rc.name == "aggressive_reset" && !r.has("recovery_behaviors") ? 4.0 * circumscribed_radius
                                                                                              : 3.0;
      rc.reset_distance = pr.number("reset_distance", fallback,
                                    "[m] obstacles within this square around the robot are kept, the rest cleared", 0.0);
      ParamValue default_names = ParamValue::ofList();
      for (const auto& n : rc.layer_names) default_names.items.push_back(ParamValue::ofString(n));
      const ParamValue names = pr.raw("layer_names", default_names, "the layers cleared", "list");
      if (names.type == ParamValue::Type::kList) {
        rc.layer_names.clear();
        for (const auto& n : names.items) {
          if (n.type == ParamValue::Type::kString) rc.layer_names.push_back(n.s);
        }
      }
      rc.affected_maps = pr.string("affected_maps", rc.affected_maps, "which costmaps: local, global or both");
      rc.force_updating = pr.boolean("force_updating", rc.force_updating, "update the costmaps at once after clearing");
      rc.invert_area_to_clear = pr.boolean("invert_area_to_clear", rc.invert_area_to_clear,
                                           "clear inside the square instead of outside it");
      if (rc.affected_maps != "local" && rc.affected_maps != "global" && rc.affected_maps != "both") {
        throw ParamError("parameter " + pr.where("affected_maps") + " must be local, global or both");
      }
    } else if (rc.kind == RecoveryKind::kRotate) {
      rc.sim_granularity = pr.number("sim_granularity", rc.sim_granularity,
                                     "[rad] step between collision checks of the turn", std::nullopt, true);
      rc.frequency = pr.number("frequency", rc.frequency, "[Hz] how often the turn command is sent", std::nullopt, true);
    } else {
      rc.distance = pr.number("back_up_distance", rc.distance, "[m] how far to back up", std::nullopt, true);
      rc.speed = pr.number("back_up_speed", std::abs(c.local.escape_vel) > 0 ? std::abs(c.local.escape_vel) : rc.speed,
                           "[m/s] backing-up speed (default: the local planner's |escape_vel|)", std::nullopt, true);
      rc.frequency = pr.number("frequency", rc.frequency, "[Hz] how often the command is sent", std::nullopt, true);
    }
    pr.reportUnknown();
  }
  c.recoveries = out;
  r.reportUnknown(skip);
  return c;
}

}  // namespace core
}  // namespace mbot
