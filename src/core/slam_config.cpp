#include "mbot_slam_navigation/core/slam_config.h"

namespace mbot {
namespace core {

SlamConfig readSlamConfig(const ParamValue& values, const std::string& ns, const Warn& warn_or_empty, double default_max_range,
                          std::vector<std::string>* unknown) {
  const Warn warn = orIgnore(warn_or_empty);
  ParamReader r(values, ns, warn);
  SlamConfig c;
  c.base_frame = r.frame("base_frame", c.base_frame, "the robot's base frame");
  c.odom_frame = r.frame("odom_frame", c.odom_frame, "the odometry frame");
  c.map_frame = r.frame("map_frame", c.map_frame, "the map frame, parent of odom_frame");
  c.map_update_interval = r.number("map_update_interval", c.map_update_interval, "[s] how often the map is published", 0.0);
  c.publish_updates = r.boolean("publish_updates", c.publish_updates,
                                "ours: publish what changed on map_updates (map_msgs/OccupancyGridUpdate) and the whole "
                                "map only when it grows (by 4 m blocks), a subscriber comes or whole_map_period passes: "
                                "for map_merge on another host (its robot_map_updates_topic)");
  c.whole_map_period = r.number("whole_map_period", c.whole_map_period,
                                "[s] ours: with publish_updates, the whole map at least this often, so that a subscriber "
                                "that lost an update is whole again",
                                std::nullopt, true);
  c.transform_publish_period = r.number("transform_publish_period", c.transform_publish_period,
                                        "[s] how often map -> odom is broadcast (0: only after each processed scan)", 0.0);
  c.occ_thresh = r.number("occ_thresh", c.occ_thresh, "occupancy above which a published cell is occupied (100)", 0.0);
  c.throttle_scans = static_cast<int>(r.integer("throttle_scans", c.throttle_scans, "process one scan in this many", 1));
  c.tf_delay = r.number("tf_delay", c.tf_delay, "[s] how far ahead map -> odom is stamped (<= 0: transform_publish_period)");
  c.correction_threshold = r.number("correction_threshold", c.correction_threshold,
                                    "[m] a correction that moves the robot more than this is published on ~correction", 0.0);
  c.scan_queue_size = static_cast<int>(
      r.integer("scan_queue_size", c.scan_queue_size, "scans held while the node is busy (gmapping's 5)", 1));
  c.backend = r.string("backend", c.backend, "graph (pose graph with loop closure) or rbpf (gmapping's particle filter)");
  if (c.backend != "graph" && c.backend != "rbpf") {
    throw ParamError("parameter " + r.where("backend") + " must be 'graph' (pose graph) or 'rbpf' (particle filter), got '" +
                     c.backend + "'");
  }

  c.session_file = r.string("session_file", c.session_file,
                            "start from this saved session (path without extension: <path>.posegraph; ~serialize_map "
                            "writes one); '' starts a new map. Graph backend");
  const ParamValue start = r.raw("map_start_pose", ParamValue::ofList(),
                                 "[m, m, rad] [x, y, yaw] of the robot's base in the session's map; [] : "
                                 "map_start_at_dock, or found by matching the first scans against the whole map",
                                 "list");
  if (start.type != ParamValue::Type::kList ||
      (!start.items.empty() && (start.items.size() != 3 || !start.items[0].isNumber() || !start.items[1].isNumber() ||
                                !start.items[2].isNumber()))) {
    throw ParamError("parameter " + r.where("map_start_pose") + " must be [x, y, yaw] (metres, radians) or [], got " +
                     start.repr());
  }
  if (!start.items.empty()) {
    c.map_start_pose = Eigen::Vector3d(start.items[0].number(), start.items[1].number(), start.items[2].number());
  }
  c.map_start_at_dock = r.boolean("map_start_at_dock", c.map_start_at_dock,
                                  "the robot stands where the session began (its first node)");
  c.mode = r.string("mode", c.mode, "mapping (the graph grows) or localization (on session_file: tracks the robot on "
                                    "the saved map, the graph does not grow)");
  if (c.mode != "mapping" && c.mode != "localization") {
    throw ParamError("parameter " + r.where("mode") + " must be 'mapping' or 'localization', got '" + c.mode + "'");
  }
  if (c.mode == "localization" && c.session_file.empty()) {
    throw ParamError("parameter " + r.where("mode") + " is 'localization', which needs a saved map: set " +
                     r.where("session_file"));
  }
  c.save_session_on_exit = r.string("save_session_on_exit", c.save_session_on_exit,
                                    "write the session to this path (without extension) when the node shuts down; '' : "
                                    "not. Graph backend");
  if (c.backend != "graph" && (!c.session_file.empty() || !c.save_session_on_exit.empty())) {
    throw ParamError("sessions (" + r.where(c.session_file.empty() ? "save_session_on_exit" : "session_file") +
                     ") are the graph backend's; " + r.where("backend") + " is '" + c.backend + "'");
  }

  // gmapping's: the matcher and updates both backends share.
  RbpfParams& p = c.rbpf;
  ScanMatcherParams& m = p.matcher;
  m.max_urange = r.number("maxUrange", default_max_range,
                          "[m] usable range: longer returns only clear space (default: the scan's range_max)");
  m.max_range = r.number("maxRange", default_max_range,
                         "[m] returns at or beyond this are no return (default: the scan's range_max)");
  m.sigma = r.number("sigma", m.sigma, "[m^2] rbpf: the scan matcher's score kernel", std::nullopt, true);
  m.kernel_size = static_cast<int>(r.integer("kernelSize", m.kernel_size, "[cells] rbpf: the search window around each return", 0));
  m.lstep = r.number("lstep", m.lstep, "[m] rbpf: the optimizer's first translation step", std::nullopt, true);
  m.astep = r.number("astep", m.astep, "[rad] rbpf: the optimizer's first rotation step", std::nullopt, true);
  m.iterations = static_cast<int>(r.integer("iterations", m.iterations, "rbpf: how often the optimizer halves its steps", 0));
  m.lsigma = r.number("lsigma", m.lsigma, "[m^2] rbpf: the likelihood kernel of a beam", std::nullopt, true);
  p.ogain = r.number("ogain", p.ogain, "rbpf: gain that smooths the particles' weights", std::nullopt, true);
  m.lskip = static_cast<int>(r.integer("lskip", m.lskip, "rbpf: beams skipped between beams used", 0));
  p.minimum_score = r.number("minimumScore", p.minimum_score, "rbpf: a match scoring less keeps the odometry pose");
  p.scan_odometry = r.boolean("scan_odometry", p.scan_odometry,
                              "rbpf: the particles move with the scan-matched track (the local_* values) instead of the "
                              "wheels' odometry");
  // The motion noise defaults to the odometry the filter moves with: gmapping's for the wheels, a
  // tenth of it for the scan-matched track (rbpf_slam.h).
  if (p.scan_odometry) p.motion = scanOdometryMotion();
  p.motion.srr = r.number("srr", p.motion.srr, "rbpf: translation error from translation (default 0.1; 0.01 on scan odometry)", 0.0);
  p.motion.srt = r.number("srt", p.motion.srt, "rbpf: translation error from rotation (default 0.2; 0.02 on scan odometry)", 0.0);
  p.motion.str = r.number("str", p.motion.str, "rbpf: rotation error from translation (default 0.1; 0.01 on scan odometry)", 0.0);
  p.motion.stt = r.number("stt", p.motion.stt, "rbpf: rotation error from rotation (default 0.2; 0.02 on scan odometry)", 0.0);
  const bool linear_set = r.has("linearUpdate");
  p.linear_update = r.number("linearUpdate", p.linear_update,
                             "[m] travel between updates: rbpf 1.0 (gmapping's), graph 0.5 (a node every half metre)", 0.0);
  p.angular_update = r.number("angularUpdate", p.angular_update, "[rad] turn between updates", 0.0);
  p.temporal_update = r.number("temporalUpdate", p.temporal_update, "[s] time between updates (< 0: off)");
  p.resample_threshold = r.number("resampleThreshold", p.resample_threshold,
                                  "rbpf: resample when the effective particle count falls below this share", 0.0);
  p.particles = static_cast<int>(r.integer("particles", p.particles, "rbpf: number of particles", 1));
  p.xmin = r.number("xmin", p.xmin, "[m] initial map extent (it grows)");
  p.ymin = r.number("ymin", p.ymin, "[m] initial map extent (it grows)");
  p.xmax = r.number("xmax", p.xmax, "[m] initial map extent (it grows)");
  p.ymax = r.number("ymax", p.ymax, "[m] initial map extent (it grows)");
  p.delta = r.number("delta", p.delta, "[m/cell] the map's resolution", std::nullopt, true);
  p.llsamplerange = r.number("llsamplerange", p.llsamplerange, "[m] rbpf: translational sampling range of the likelihood", 0.0);
  p.llsamplestep = r.number("llsamplestep", p.llsamplestep, "[m] rbpf: translational sampling step of the likelihood", 0.0);
  p.lasamplerange = r.number("lasamplerange", p.lasamplerange, "[rad] rbpf: angular sampling range of the likelihood", 0.0);
  p.lasamplestep = r.number("lasamplestep", p.lasamplestep, "[rad] rbpf: angular sampling step of the likelihood", 0.0);
  p.seed = static_cast<unsigned>(r.integer("seed", static_cast<long>(p.seed), "rbpf: the random generator's seed", 0));
  p.threads = static_cast<int>(r.integer("threads", p.threads, "rbpf: threads matching the particles (same result)", 1));
  p.best_switch_margin = r.number("best_switch_margin", p.best_switch_margin,
                                  "rbpf: how much more weight another lineage needs before the published particle switches "
                                  "(0: gmapping's best at every update)",
                                  0.0);

  // The pose graph's own (also the rbpf's track with scan_odometry).
  GraphSlamParams& g = c.graph;
  g.match_max_range = r.number("match_max_range", g.match_max_range, "[m] returns farther than this are not matched",
                               std::nullopt, true);
  g.match_sigma = r.number("match_sigma", g.match_sigma, "[m] likelihood kernel of the loop-closure submaps", std::nullopt, true);
  g.local_match_sigma = r.number("local_match_sigma", g.local_match_sigma,
                                 "[m] likelihood kernel of the local map scans are tracked in (<= 0: match_sigma)");
  g.local_map_nodes = static_cast<int>(r.integer("local_map_nodes", g.local_map_nodes, "nodes in the local map", 1));
  g.local_search_window = r.number("local_search_window", g.local_search_window,
                                   "[m] +- x, y searched around odometry's prediction (the least, see local_search_sigmas)",
                                   std::nullopt, true);
  g.local_search_sigmas = r.number("local_search_sigmas", g.local_search_sigmas,
                                   "the window widens to this many times odometry's recent rms error (0: fixed)", 0.0);
  g.local_search_max_window = r.number("local_search_max_window", g.local_search_max_window,
                                       "[m] the widest tracking window", std::nullopt, true);
  g.local_search_angle = r.number("local_search_angle", g.local_search_angle, "[rad] +- yaw searched when tracking",
                                  std::nullopt, true);
  g.local_min_score = r.number("local_min_score", g.local_min_score,
                               "a match scoring below this keeps odometry's prediction", 0.0);
  g.local_prior_margin = r.number("local_prior_margin", g.local_prior_margin,
                                  "the match nearest odometry is kept when within this share of the best score", 0.0);
  g.local_prior_weight = r.number("local_prior_weight", g.local_prior_weight,
                                  "[1/m^2] least weight of odometry's prediction in the match", 0.0);
  g.local_prior_points = r.number("local_prior_points", g.local_prior_points,
                                  "odometry's weight follows its recent error along the directions scans pin, the score "
                                  "counted as this many returns (0: local_prior_weight throughout)",
                                  0.0);
  g.local_visible_only = r.boolean("local_visible_only", g.local_visible_only,
                                   "track with only the returns the local map could have seen");
  g.local_visible_side = r.boolean("local_visible_side", g.local_visible_side,
                                   "and only from the side each return faces (no matching the far face of a wall)");
  g.submap_nodes = static_cast<int>(r.integer("submap_nodes", g.submap_nodes, "nodes per loop-closure submap", 1));
  g.loop_search_radius = r.number("loop_search_radius", g.loop_search_radius,
                                  "[m] loop-closure search window right after a closure", 0.0);
  g.loop_search_growth = r.number("loop_search_growth", g.loop_search_growth,
                                  "[m/m] how the window grows per metre travelled since", 0.0);
  g.loop_search_max_radius = r.number("loop_search_max_radius", g.loop_search_max_radius,
                                      "[m] the widest loop-closure window", 0.0);
  g.loop_search_reach = r.number("loop_search_reach", g.loop_search_reach,
                                 "[m] submaps with a node within the window plus this are tried", 0.0);
  g.loop_search_angle = r.number("loop_search_angle", g.loop_search_angle, "[rad] +- yaw of the loop search", 0.0);
  g.loop_min_response = r.number("loop_min_response", g.loop_min_response, "mean likelihood a closure must reach", 0.0);
  g.loop_ambiguity = r.number("loop_ambiguity", g.loop_ambiguity,
                              "a second pose scoring this share of the best rejects the closure", 0.0);
  g.loop_sigma_distance = r.number("loop_sigma_distance", g.loop_sigma_distance,
                                   "[m] a closure's uncertainty grows with its distance from the submap on this scale "
                                   "(0: as a chain edge)",
                                   0.0);
  g.loop_visible_shift = r.number("loop_visible_shift", g.loop_visible_shift,
                                  "[m] a closure re-measured with only the returns its submap saw is kept within this (0: off)",
                                  0.0);
  g.loop_candidates = static_cast<int>(r.integer("loop_candidates", g.loop_candidates, "nearest submaps tried per node", 0));
  g.loop_recent_submap = r.boolean("loop_recent_submap", g.loop_recent_submap,
                                   "also match each node against the newest submap that has left the local map");
  g.redundant_distance = r.number("redundant_distance", g.redundant_distance,
                                  "[m] a node this near an older one keeps its scan only while needed (0: all keep theirs)",
                                  0.0);
  g.redundant_angle = r.number("redundant_angle", g.redundant_angle, "[rad] and within this of its heading", 0.0);
  g.keep_trimmed_scans = r.boolean("keep_trimmed_scans", g.keep_trimmed_scans,
                                   "a trimmed node keeps its scan for the map (memory grows with the scans)");
  g.loop_solve_chi2 = r.number("loop_solve_chi2", g.loop_solve_chi2,
                               "new closures that all fit the estimate below this squared error trigger no solve (0: always)",
                               0.0);
  // The graph's own linearUpdate default (a node every 0.5 m) unless the user set linearUpdate.
  if (linear_set) g.linear_update = p.linear_update;
  p.tracking = g;
  if (r.has("base_link")) {
    // The car tutorial's launch file sets it; too unlike base_frame for the spelling check.
    r.markRead("base_link");
    warn("unknown parameter " + r.where("base_link") + " (did you mean base_frame?); it is ignored");
  }
  std::vector<std::string> left = r.reportUnknown();
  // Keys the other backend reads: known, but without effect here.
  static const std::vector<std::string> kRbpfOnly = {
      "sigma", "kernelSize", "lstep", "astep", "iterations", "lsigma", "ogain", "lskip", "minimumScore", "scan_odometry",
      "srr", "srt", "str", "stt", "resampleThreshold", "particles", "llsamplerange", "llsamplestep", "lasamplerange",
      "lasamplestep", "seed", "threads", "best_switch_margin"};
  static const std::vector<std::string> kGraphOnly = {
      "match_sigma", "submap_nodes", "loop_search_radius", "loop_search_growth", "loop_search_max_radius",
      "loop_search_reach", "loop_search_angle", "loop_min_response", "loop_ambiguity", "loop_sigma_distance",
      "loop_visible_shift", "loop_candidates", "loop_recent_submap", "redundant_distance", "redundant_angle",
      "keep_trimmed_scans", "loop_solve_chi2"};
  for (const auto& key : c.backend == "graph" ? kRbpfOnly : kGraphOnly) {
    if (!r.has(key)) continue;
    warn("parameter " + r.where(key) + " has no effect with the " + c.backend + " backend");
    left.push_back(key);
  }
  if (unknown) *unknown = left;
  return c;
}

}  // namespace core
}  // namespace mbot
