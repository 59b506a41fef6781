// Pose-graph SLAM (the slam_gmapping node's `~backend: graph`), in the manner of Karto and
// Cartographer:
//
// Local SLAM. Every scan is tracked: its pose, predicted by odometry from the previous scan's, is
// corrected by correlative matching (branch and bound over a window as wide as odometry's record
// asks, local_search_sigmas, then refinement; see correlative_matcher.h) against a likelihood grid
// of the last `local_map_nodes` nodes' scans.
// Every linearUpdate metres, angularUpdate radians or temporalUpdate seconds of odometry the
// tracked scan becomes a node, joined by an edge to the previous node, and the local map is rebuilt.
//
// Loop closure. Every `submap_nodes` nodes form a submap: their scans in the frame of the first
// (the anchor), as a likelihood grid that is kept. Each new node is matched against the finished
// submaps that have a node within the search radius plus loop_search_reach of its estimate; the
// radius grows with the distance travelled since the last accepted closure (drift) from
// loop_search_radius to loop_search_max_radius, and the window of the branch-and-bound search is
// that radius (the reach only widens which submaps are tried). A match
// becomes an edge (anchor -> node) only if its response reaches loop_min_response and it is not
// ambiguous: no other pose at least 0.3 m or 0.1 rad away scores within loop_ambiguity of it
// (a corridor, a row of doors). It weighs less the farther from the submap's nodes the scan was
// matched (loop_sigma_distance): such a scan shares with them only what lies on their side, and
// its match leans that way. With loop_recent_submap, each node is also matched against the newest
// submap just behind its local map (within loop_search_reach, in the tracking window): those
// scans are not in the local map, so the match measures the chain over the last few tens of nodes
// afresh; such closures do not count as closures for the search radius's drift.
//
// Optimization. After new closures the graph is solved (pose_graph.h) unless every new closure
// agrees with the current estimate (error below loop_solve_chi2; a robot revisiting a well-mapped
// home): a solve would move nothing, and its cost grows with the graph. Such closures join the
// next solve, which comes at the latest after kMaxUnsolved of them (or at flush()). A solve runs
// first with a wide Cauchy loss, then with the nominal one, so that consistent closures pull fully and a wrong one is
// down-weighted; a closure still inconsistent with the rest afterwards (Mahalanobis error above
// loop_reject_chi2) is removed and the graph solved again. This runs in a background thread
// (`background`), so processScan never waits for it; nodes added meanwhile move with the last
// optimized node.
//
// Map. A gmapping counting grid (slam_grid.h) of every node's scan at its optimized pose. Nodes
// are added as they come; the grid is rebuilt from all nodes only after an optimization moved some
// node by more than half a cell or 0.5 degree from where the grid drew it.
//
// A robot left running in one home revisits the same places for hours; memory must not grow with
// time. A new node within redundant_distance of an older node that keeps its scan, and within
// redundant_angle of its heading (any heading if the laser sees all round), is redundant: it joins
// the chain and is matched against the nearest submap (so the robot stays anchored to the old
// map), but once the local map and its submap no longer need it, its scan is freed (so the map,
// when rebuilt, no longer counts what it saw; keep_trimmed_scans keeps it for the map only), and a
// submap made mostly of redundant nodes is not kept. Match points are freed from every node at
// that point. The trimmed node then leaves the
// optimization too: its two chain edges become one (the measurements composed, the covariances
// propagated) and its closures move to the live node before it (composed with the chain edge
// between them; of several from one submap to that node, the least uncertain stays): they are
// what ties a revisit, and so the loop it closes, to the map. It keeps its pose relative to the
// node before it, and moves with it. What is kept and
// solved then grows with the area seen, not with the time spent (a merged node's ~0.1 KB remains).
//
// Frames and units: as slam_backend.h.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/correlative_matcher.h"
#include "mbot_slam_navigation/core/pose_graph.h"
#include "mbot_slam_navigation/core/scan_matcher.h"
#include "mbot_slam_navigation/core/slam_backend.h"
#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace core {

// The parameters' ROS names, units and meanings are in slam_config.cpp (the reader) and on the
// reference page docs/nodes/slam_gmapping.md; here, what each does inside the graph and why its
// default is what it is. docs/slam.md has the measurements behind the defaults.
struct GraphSlamParams {
  /// [m] `linearUpdate`: a node every this much travel. Half gmapping's 1 m (the rbpf keeps that),
  /// so that the scan the next scans are tracked against is at most 0.5 m behind them.
  double linear_update = 0.5;
  double angular_update = 0.5;      ///< [rad] `angularUpdate`
  double temporal_update = -1.0;    ///< [s] `temporalUpdate`; < 0 disables
  double delta = 0.05;              ///< [m] map resolution (`delta`), also the matching resolution
  double xmin = -100, ymin = -100, xmax = 100, ymax = 100;  ///< [m] initial map extent (grows)
  /// Map registration: laser pose in the base frame, `maxUrange`, `maxRange`.
  ScanMatcherParams matcher;

  double match_max_range = 30.0;    ///< [m] returns farther than this are not matched (`~match_max_range`)
  double match_sigma = 0.075;       ///< [m] likelihood kernel of the loop-closure submaps (`~match_sigma`)
  /// [m] likelihood kernel of the local map that every scan is tracked in (`~local_match_sigma`);
  /// <= 0: match_sigma. A narrower kernel holds the heading better but did not make better maps.
  double local_match_sigma = -1.0;
  /// Nodes in the local map (`~local_map_nodes`): 40 at 0.5 m keep 20 m of travel to track against.
  int local_map_nodes = 40;
  /// [m] +- x, y around the odometry prediction (`~local_search_window`); the least window when it
  /// widens with local_search_sigmas.
  double local_search_window = 0.15;
  /// The window follows odometry's record (`~local_search_sigmas`): this many times r, the root
  /// mean square of how far the best match moved the prediction over the last 200 scans, in every
  /// direction (local_prior_points counts only those the matches pinned), within
  /// [local_search_window, local_search_max_window]. Odometry that slips needs a window its worst
  /// steps fit in; good odometry keeps a narrow one, where a wider window lets the tracked pose slip
  /// along a corridor. 0 keeps local_search_window throughout.
  double local_search_sigmas = 10.0;
  double local_search_max_window = 0.3;  ///< [m] (`~local_search_max_window`)
  double local_search_angle = 0.15; ///< [rad] +- yaw (`~local_search_angle`)
  double local_min_score = 0.25;    ///< below: keep the odometry prediction (`~local_min_score`)
  /// The match climbed from the odometry prediction, held to it by the prior's weight, is kept
  /// when it scores within this fraction of the best match in the window (`~local_prior_margin`):
  /// where the scan does not fix the pose (along a corridor) the best score is one of many nearly
  /// equal ones, and the map, seen from behind the robot, scores a little higher the farther back
  /// the scan is put. 0 always takes the best.
  double local_prior_margin = 0.03;
  /// [1/m^2] score lost per square metre away from the prediction in that climb
  /// (`~local_prior_weight`), while local_prior_points is 0 or fewer than 50 scans were tracked.
  double local_prior_weight = 5.0;
  /// How much odometry's prediction weighs against the scan, from how good odometry has been
  /// (`~local_prior_points`): the climb's weight is 1 / (2 N r^2), r the root mean square of how
  /// far the best match moved the prediction over the last 200 scans, N this value (the score
  /// counted as N independent returns), kept within [local_prior_weight, 5000]. r is measured only
  /// along the directions each match pinned, in x, y and yaw together (its score curves down there
  /// as if a tenth of the returns, and at least 10, lay on surfaces square to it; matchDirections):
  /// along a plain corridor or one wall the best match lies anywhere in the window, and counting it
  /// would make good odometry look bad. Where odometry is good the prior holds what the scan says
  /// little of, and the directions a match leaves open are weighed against its prediction
  /// (matchLocally); where it slips the weight stays near local_prior_weight and the scan decides.
  /// 0 keeps local_prior_weight throughout.
  double local_prior_points = 130.0;
  /// Track a scan only with the returns that the local map's scans could have seen (Visibility in
  /// correlative_matcher.h; `~local_visible_only`): the others, what came into view as the robot
  /// drove on, pull the match back and shorten the map.
  bool local_visible_only = true;
  /// And only what they saw from the side each return faces (`~local_visible_side`; the normal
  /// from its neighbours in the scan, surfaceNormals): through a door the robot sees the other face
  /// of the wall beside it, a wall's thickness behind the face the local map holds, and matching it
  /// shifts the scan. It costs accuracy on logs with noisier odometry, so it is off by default and
  /// `explore.launch` (the simulated worlds) turns it on. When fewer than half the returns pass,
  /// tracking takes all but those on the other face of a wall the local map saw from its far side
  /// (Visibility::notBehindOf).
  bool local_visible_side = false;
  int submap_nodes = 10;            ///< nodes per loop-closure submap (`~submap_nodes`)
  /// [m] The search radius, the window of a closure's search: how far the estimate may have
  /// drifted, right after a closure (`~loop_search_radius`), growing by loop_search_growth per metre
  /// travelled since (`~loop_search_growth`) to loop_search_max_radius (`~loop_search_max_radius`).
  /// A window wider than the drift finds the place next door in a row of like rooms.
  double loop_search_radius = 1.0;
  double loop_search_growth = 0.01;       ///< [m per m travelled] (`~loop_search_growth`)
  double loop_search_max_radius = 6.0;    ///< [m] (`~loop_search_max_radius`)
  /// [m] Submaps with a node within the search radius plus this are tried (`~loop_search_reach`):
  /// a scan shares much of what a submap's nodes saw from a few metres off them, and exploring
  /// a large floor the robot seldom passes within the radius of where it was. The window stays the
  /// search radius.
  double loop_search_reach = 2.0;
  double loop_search_angle = 0.35;  ///< [rad] +- yaw of the loop search (`~loop_search_angle`)
  double loop_min_response = 0.55;  ///< mean likelihood a closure must reach (`~loop_min_response`)
  double loop_ambiguity = 0.9;      ///< a second pose scoring this share of the best rejects it (`~loop_ambiguity`)
  int loop_candidates = 3;          ///< nearest submaps tried per node (`~loop_candidates`)
  /// Also match each node against the newest submap whose nodes have all left its local map, if
  /// one of them lies within loop_search_reach (`~loop_recent_submap`). The older submaps alone are
  /// loops (the local map may still overlap the one in between); without this, nothing but the
  /// chain of tracked edges holds a node to the last 30 nodes, and the chain's heading wanders.
  /// Searched in the tracking window (local_search_max_window, local_search_angle), not the drift's:
  /// the chain since is short.
  bool loop_recent_submap = true;
  /// [m] A closure's standard deviations grow with d, the distance from the matched pose to the
  /// nearest node of the submap, as sqrt(1 + (d / this)^2) (`~loop_sigma_distance`): a scan taken
  /// farther off sees less of what the submap saw, and the match leans towards it. 0: every
  /// closure weighs as a chain edge.
  double loop_sigma_distance = 0.25;
  /// [m] A closure is measured again with only the returns its submap saw, from the side of the
  /// surface they face (`~loop_visible_shift`): the other face of a wall, seen from beyond it, pulls
  /// the match towards the submap by up to the wall's thickness. The second measurement is kept
  /// when it lies within this distance (and 0.05 rad) of the first and at least a quarter of the
  /// returns were seen. 0: measured once, with all returns.
  double loop_visible_shift = 0.15;
  double loop_reject_chi2 = 50.0;   ///< closures above this error after optimizing are removed
  double edge_sigma_xy = 0.03;      ///< [m] standard deviation of an edge's translation
  double edge_sigma_theta = 0.01;   ///< [rad] and of its rotation
  double cauchy_scale = 3.0;        ///< Cauchy loss scale of closures, in standard deviations
  /// New closures all with a squared Mahalanobis error at the current estimate below this (7.8: 95%
  /// for 3 degrees of freedom) do not trigger a solve (`~loop_solve_chi2`); 0 solves after every closure.
  double loop_solve_chi2 = 7.8;
  /// [m] a new node this close to an older node that keeps its scan (and within redundant_angle of
  /// its heading, unless the laser sees all round) keeps its scan only while the local map and its
  /// submap need it (`~redundant_distance`); 0 keeps every node's scan.
  double redundant_distance = 0.3;
  double redundant_angle = 0.5;     ///< [rad] (`~redundant_angle`; not used for a laser that sees all round)
  /// A trimmed node still leaves the optimization and frees its match points, but keeps its scan
  /// for the map (`~keep_trimmed_scans`): a map rebuilt after a closure then still counts what it
  /// saw (a revisit's scans show door jambs and furniture sides at other angles; without them an
  /// explorer chases the frontiers that come back). Memory then grows with the scans taken.
  bool keep_trimmed_scans = false;
  /// Keep every scan's tracked pose for scanPoses() (offline scoring; 40 bytes a scan, so the node
  /// turns it off).
  bool keep_scan_poses = true;
  bool background = true;           ///< optimize in a background thread (false: inline, deterministic)
  /// false: tracking only (the particle filter's scan odometry, rbpf_slam.h): every scan tracked
  /// against the local map as above, but no submaps, no closure search, no optimization, and a
  /// node's scan freed once it leaves the local map, so that memory stays flat; occupancy() then
  /// draws the local map's nodes only. Not a ROS parameter.
  bool closures = true;
  /// Throws std::invalid_argument naming the ROS parameter when a value is unusable.
  void validate() const;
};

struct GraphSlamStats {
  int nodes = 0;
  int local_match_failures = 0;     ///< nodes left at the odometry prediction
  double innovation_rms = 0.0;      ///< [m] how far matches moved the prediction (local_search_sigmas)
  /// [m] and in the directions the matches pinned (local_prior_points), as a 2-d distance
  double pinned_innovation_rms = 0.0;
  double search_window_m = 0.0;     ///< [m] the tracking window at the last scan (local_search_sigmas)
  double prior_weight = 0.0;        ///< [1/m^2] the climb's weight at the last scan
  /// [0, 1] how far odometry decided the directions the last match left open (kTrustedOdometryCells)
  double odometry_trust = 0.0;
  /// [m] How weakly the last tracked scan fixed its position: the standard deviation along the
  /// direction its match constrains least (matchDirections: x, y and the yaw in metres at the
  /// returns' mean range; the score counted as local_prior_points returns, a cautious count). About
  /// 1 cm in a room, 5-6 cm or more along a plain corridor, more beside a lone pillar.
  double match_weakest_m = 0.0;
  int loop_attempts = 0;            ///< submap matches tried
  int loop_closures = 0;            ///< closure edges in the graph
  int closures_accepted = 0;        ///< closures ever accepted (some since merged into others)
  int closures_moved = 0;           ///< closures moved from a merged node to the node before it
  int closures_remeasured = 0;      ///< closures accepted as measured again with what their submap saw (loop_visible_shift)
  /// closures accepted in part: ambiguous only along one direction (a plain wall seen again), their
  /// information kept in the directions the match pins
  int closures_partial = 0;
  int closures_recent = 0;          ///< closures accepted to the submap just behind the local map (loop_recent_submap)
  int merged_nodes = 0;             ///< trimmed nodes taken out of the optimization
  int loop_rejected_ambiguous = 0;
  int loop_rejected_inconsistent = 0;  ///< removed after optimization
  int optimizations = 0;
  int closures_unsolved = 0;        ///< closures that agreed with the estimate and await the next solve
  /// Nodes waiting for the closure search now, and the most that ever waited (with `background`:
  /// the closure thread's backlog, which grows when the machine cannot give it the time it needs).
  int closure_backlog = 0;
  int closure_backlog_max = 0;
  double last_optimization_ms = 0.0;
  double search_radius_m = 0.0;     ///< current loop search radius
  int redundant_nodes = 0;          ///< nodes found redundant (redundant_distance)
  int trimmed_nodes = 0;            ///< of those, nodes whose scan and points are freed
  int submaps = 0;                  ///< submaps kept for closures
  int submaps_skipped = 0;          ///< submaps not kept (mostly redundant nodes)
  std::size_t submap_bytes = 0;     ///< the kept submaps' grids with the pooled levels cached
};

/// A saved session that cannot be read: what is wrong with it (the caller names the file).
class SessionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class GraphSlam : public SlamBackend {
 public:
  explicit GraphSlam(const GraphSlamParams& params);
  ~GraphSlam() override;
  GraphSlam(const GraphSlam&) = delete;
  GraphSlam& operator=(const GraphSlam&) = delete;

  bool processScan(const Eigen::Vector3d& odom_pose, const LaserScan& scan, double time_s) override;
  Eigen::Vector3d currentPose() const override;
  std::vector<TrajectoryNode> trajectory() const override;
  /// Safe to call from a thread other than processScan's: the map is built under its own lock from
  /// node poses copied under the graph's (a rebuild after an optimization moved them can take
  /// tenths of a second, and processScan does not wait for it).
  OccupancyImage occupancy(double occ_thresh) const override;
  bool mapOutdated() const override;  ///< does not wait for a rebuild in progress
  bool tracksEveryScan() const override { return true; }
  double trackingWeakestSigma() const override;
  int updates() const override;

  /// Waits until the background thread has searched every node for closures, then solves the
  /// graph if closures await a solve (for offline runs and tests; the node never calls it).
  void flush();
  GraphSlamStats stats() const;
  /// Every tracked scan's pose (time [s], base in map), each moved with the node before it by every
  /// optimization since: a finer trajectory than the nodes alone. Empty unless keep_scan_poses.
  std::vector<std::pair<double, Eigen::Vector3d>> scanPoses() const;
  /// The graph's edges (chain and closures), for drawing and tests.
  std::vector<PoseGraphEdge> edges() const;
  const GraphSlamParams& params() const { return params_; }

  // Sessions (slam_toolbox's serialize_map / deserialize_map). A session file holds a format
  // version, the backend's name, the laser's pose and ranges the scans were taken with, every
  // node (pose, odometry, time, distance travelled, its scan if kept, how it was merged), the
  // edges, the submaps' node ranges and the tracked scans' poses (keep_scan_poses); its last 8 bytes are a checksum of the rest, so a
  // truncated or damaged file is told from a good one. Binary, little-endian.

  /// Writes the session to `out` (waits for the closure search of the nodes so far: flush()).
  void saveSession(std::ostream& out);
  /// A GraphSlam holding the session in `bytes` (a whole file), with `params` for what comes next;
  /// the laser's pose and ranges are the session's (`notes` gets a sentence for each that differs
  /// from `params`). The submaps are rebuilt from the nodes' scans. The next scan joins it as
  /// resume() says. Throws SessionError.
  static std::unique_ptr<GraphSlam> loadSession(const std::string& bytes, const GraphSlamParams& params,
                                               std::string* notes = nullptr);
  /// How the next scans join a loaded session: the robot's base near `pose` (the session's map
  /// frame; searched within resume_window_m and resume_angle_rad of it), or, without a pose,
  /// anywhere on the session's map (the whole map searched, every heading: global matching). With
  /// `localization`, scans are then tracked against the saved nodes near the robot and the graph
  /// does not grow (slam_toolbox's localization mode); without, new nodes extend the graph from
  /// there, their loop closures reaching the saved part. Until a scan matches, processScan()
  /// returns false and resumeFailure() says why.
  void resume(const std::optional<Eigen::Vector3d>& pose, bool localization);
  /// Why the last scan did not join the session (empty once it has, or before any tried).
  std::string resumeFailure() const;
  /// Whether scans still wait to join a loaded session.
  bool resuming() const;
  bool localizing() const;
  /// The session's first node (the dock: map_start_at_dock); the origin for an empty graph.
  Eigen::Vector3d firstPose() const;
  static constexpr double kResumeWindow = 0.5;   ///< [m] +- x, y around a given start pose
  static constexpr double kResumeAngle = 0.35;   ///< [rad] +- yaw around it
  static constexpr uint32_t kSessionVersion = 1;
  /// [m] localization: the local map (saved nodes near the robot, and the last kTemporaryNodes
  /// scans as temporary nodes) is built again when the robot has moved this far
  static constexpr double kLocalizeRebuild = 1.0;
  static constexpr std::size_t kTemporaryNodes = 10;
  /// [m], [rad] localization: a scan is matched once odometry moved this far since the last match
  static constexpr double kLocalizeStep = 0.1;
  static constexpr double kLocalizeTurn = 0.02;

 private:
  struct Node {
    Eigen::Vector3d pose;   // base in map, optimized
    Eigen::Vector3d odom;   // base in odom
    double time_s;
    double travelled_m;     // odometry path length from the first node
    std::shared_ptr<const LaserScan> scan;  // null once trimmed
    std::shared_ptr<const std::vector<Eigen::Vector2d>> points;  // match points, base frame; null once no longer needed
    bool redundant;          // an older node that keeps its scan saw the same place
    bool anchor = false;     // the first node of a kept submap (never merged)
    int parent = -1;         // merged: the live node before it, which it moves with
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // merged: its pose in the parent's frame
    // Where occupancy() last drew its scan (written there, under mutex_): an optimization that
    // moves it from there by more than half a cell or 0.5 degree, in one solve or over several,
    // outdates the map.
    mutable Eigen::Vector3d drawn_pose = Eigen::Vector3d::Zero();
    mutable bool drawn = false;
  };
  struct TrackedScan {
    double time_s;
    int node;                // the last node before it (or itself)
    Eigen::Vector3d offset;  // its pose in that node's frame
  };
  struct Submap {
    int first, last;        // node indices [first, last]; first is the anchor
    std::shared_ptr<const LikelihoodGrid> grid;  // in the anchor's frame
    std::shared_ptr<const Visibility> seen;      // what its nodes' scans saw, anchor frame (null: not kept)
  };

  Eigen::Vector3d matchLocally(const Eigen::Vector3d& predicted, const std::vector<Eigen::Vector2d>& points);
  /// processScan while resuming: finds the scan on the session's map and joins it (graph_session.cpp).
  bool resumeWith(const Eigen::Vector3d& odom, const LaserScan& scan, double time_s);
  /// processScan in localization mode after the robot was found: tracks the scan only.
  bool localize(const Eigen::Vector3d& odom, const LaserScan& scan, double time_s);
  /// A local map of the saved nodes nearest `pose` (those with their scans, within the match
  /// reach) and the temporary nodes, in the map frame; null if none (mutex_ held).
  std::unique_ptr<LikelihoodGrid> sessionMapNearLocked(const Eigen::Vector3d& pose, Visibility* seen) const;
  /// Whether node n completes a submap (submaps count from the session's start: session_start_).
  bool completesSubmap(int n) const { return n >= session_start_ && (n + 1 - session_start_) % params_.submap_nodes == 0; }
  void rebuildLocalMapLocked();  // mutex_ held
  void backgroundLoop();
  /// Closure search for one node and the submap that it completes; returns true if it added an
  /// edge that the current estimate does not already satisfy (loop_solve_chi2).
  bool searchClosures(int node);
  /// A closure whose second-best match `other` lies along the one direction its best `found` leaves
  /// open (a plain wall seen again, matched anywhere along it): the projection onto the two
  /// directions it pins (x, y, yaw of the node in the submap's frame), so that it constrains the
  /// distance to the wall and the heading and leaves the rest to the chain. nullopt otherwise.
  std::optional<Eigen::Matrix3d> partialClosure(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                                                const Eigen::Vector3d& found, const Eigen::Vector3d& other) const;
  void buildSubmap(int first, int last);
  /// Whether a node at `pose` would repeat an older node that keeps its scan: within
  /// redundant_distance, and within redundant_angle of its heading unless the laser sees
  /// `all_round` (mutex_ held).
  bool redundantLocked(const Eigen::Vector3d& pose, bool all_round) const;
  /// [m] returns farther than this are not matched: match_max_range, or maxUrange if shorter.
  double matchReach() const { return std::min(params_.match_max_range, params_.matcher.max_urange); }
  double localSigma() const { return params_.local_match_sigma > 0.0 ? params_.local_match_sigma : params_.match_sigma; }
  /// Frees the match points of nodes that neither the local map nor a submap still needs, and the
  /// scans of such nodes that are redundant, which then leave the optimization (mutex_ held).
  void trimLocked();
  /// Takes trimmed node `k` out of the optimization: its chain edges joined, its closures dropped
  /// (mutex_ held).
  void mergeLocked(int k);
  /// Moves `grid` to the front of pyramids_ and frees the pooled levels of those past the budget.
  void cachePyramid(const std::shared_ptr<const LikelihoodGrid>& grid);
  void optimize();
  Eigen::Matrix3d edgeInformation(double scale) const;

  GraphSlamParams params_;
  ScanMatcher registrar_;  // map registration (gmapping's beam rules)

  mutable std::mutex mutex_;  // nodes_, edges_, submaps_, stats_, last_odom_
  std::condition_variable work_cv_, idle_cv_;
  std::vector<Node> nodes_;
  std::vector<PoseGraphEdge> edges_;
  std::vector<Submap> submaps_;
  std::vector<TrackedScan> scans_;
  std::deque<int> pending_;  // nodes not yet searched for closures
  std::deque<int> redundant_;  // redundant nodes whose scans are still held, oldest first
  int submapped_upto_ = -1;  // last node whose submap has been built (or skipped) and searched
  int released_upto_ = -1;   // last node whose match points have been freed
  int unsolved_ = 0;         // closures added since the last solve that did not ask for one
  static constexpr int kMaxUnsolved = 10;  // after this many, they are solved anyway
  // Submap grids whose pooled levels are kept, most recently matched first (closure thread only),
  // and the bytes they may hold (grids and levels; the most recent is kept whatever its size).
  // 16-bit cells: 8 MiB holds as many as 4 MiB of 8-bit ones did (with 4 MiB FR079 took 20%
  // more CPU, rebuilding levels).
  static constexpr std::size_t kPyramidBytes = 8u << 20;
  // [rad] the most the second climb of a closure (loop_visible_shift) may turn it
  static constexpr double kMaxVisibleTurn = 0.05;
  // [m] neighbouring returns farther apart lie on different surfaces: no normal (surfaceNormals)
  static constexpr double kSurfaceGap = 0.3;
  // [m] how far behind a face the scans saw its wall's other face may lie (Visibility::notBehindOf):
  // the generated worlds' 0.1 m walls, seen at up to 60 degrees off square, and a pose's slack
  static constexpr double kWallBehind = 0.25;
  std::list<std::shared_ptr<const LikelihoodGrid>> pyramids_;
  bool busy_ = false, stop_ = false;
  GraphSlamStats stats_;  // counters; nodes and loop_closures are derived in stats()
  double last_closure_travelled_ = 0.0;

  Eigen::Vector3d last_odom_ = Eigen::Vector3d::Zero();
  // Scan tracking (processScan's thread): the local map, the last node's pose when it was built
  // (its frame), and the latest scan's matched pose in that frame with its odometry.
  std::unique_ptr<LikelihoodGrid> local_map_;
  Visibility local_seen_;  // what the local map's scans saw, in its frame
  Eigen::Vector3d local_anchor_ = Eigen::Vector3d::Zero(), track_pose_ = Eigen::Vector3d::Zero(),
                  track_odom_ = Eigen::Vector3d::Zero();
  // local_prior_points: the running mean of squared innovations [m^2] over about
  // kInnovationWindow scans, and how many there were.
  static constexpr double kInnovationWindow = 200.0;
  static constexpr int kInnovationWarmup = 50;
  static constexpr double kMaxPriorWeight = 5000.0;  // [1/m^2]
  // A direction counts as pinned by a match (for odometry's record) when the score curves down
  // along it by this share of what a scan whose every return pinned it would give (1 / sigma^2).
  static constexpr double kConstrainedShare = 0.1;
  // And by at least this many returns' worth (the mean score's curvature times n sigma^2, n the
  // returns): a few returns of a wall at the laser's reach pin nothing for sure. A direction below
  // this is open: weighed against odometry's prediction (matchLocally).
  static constexpr double kMinPinnedReturns = 10.0;
  // The curvatures [score/m^2] at and above which a direction of a match of `returns` returns in a
  // grid of kernel `sigma` [m] is pinned, and below which it is open (the two rules above).
  static double pinnedCurvature(double returns, double sigma) {
    return std::max(kConstrainedShare, kMinPinnedReturns / returns) / (sigma * sigma);
  }
  static double openCurvature(double returns, double sigma) { return kMinPinnedReturns / returns / (sigma * sigma); }
  // One match's squared innovation enters odometry's record clipped at this many times the record's
  // mean (3 sigma): a single wrong match must not make good odometry look bad.
  static constexpr double kInnovationClip = 9.0;
  // Odometry decides the open directions once its record (the pinned innovations' rms) is within
  // this many map cells a scan, and not at all from twice that: the simulator's 3-5 mm are within,
  // the Radish logs' 18-50 mm (wheels that slip, where the scan knows better) are not.
  static constexpr double kTrustedOdometryCells = 0.2;
  // [m] A closure's second-best match may differ from the best across its open direction by this
  // much (in x, y and the scaled yaw) and still count as the same wall matched elsewhere along it.
  static constexpr double kPartialAcross = 0.1;
  double innovation2_ = 0.0;
  long innovations_ = 0;
  // The same over the directions each match pinned (the prior's weight), per direction times 2.
  double pinned_innovation2_ = 0.0;
  long pinned_innovations_ = 0;

  // Sessions: nodes before session_start_ were loaded from a file (rebuildLocalMapLocked tops the
  // local map up with those near the robot); resume_ says how the next scan joins them.
  int session_start_ = 0;
  bool resume_pending_ = false, localization_ = false;
  std::optional<Eigen::Vector3d> resume_pose_;
  std::string resume_failure_;
  std::unique_ptr<LikelihoodGrid> session_grid_;  // the whole saved map, for global matching
  Eigen::Vector3d localized_at_ = Eigen::Vector3d::Zero();  // where the localization's local map was built
  // localization's temporary nodes (map frame pose, scan), oldest first
  std::deque<std::pair<Eigen::Vector3d, std::shared_ptr<const LaserScan>>> temporary_;

  double search_window_ = 0.0;  // [m] the tracking window for the next scan (local_search_sigmas)
  double linear_distance_ = 0.0, angular_distance_ = 0.0, last_update_time_ = 0.0, travelled_ = 0.0;

  mutable std::mutex map_mutex_;  // the map cache
  mutable SlamGrid map_;
  mutable int map_nodes_ = 0;     // nodes registered in map_
  mutable OccupancyImage map_image_;  // map_'s picture as occupancy() last returned it
  mutable double map_image_thresh_ = -1.0;
  // Read without map_mutex_ (mapOutdated), so that a scan's processing never waits for a rebuild.
  mutable std::atomic<bool> map_dirty_{false};

  std::thread worker_;
};

/// The session file of a slam_toolbox-style `filename` (the path without extension):
/// <filename>.posegraph, with a leading ~ expanded ($HOME); a filename ending in .posegraph is kept.
std::string sessionPath(const std::string& filename);
/// Saves `slam`'s session to `path` atomically: written to a temporary file beside it, flushed to
/// disk and renamed over it, so that a crash mid-write leaves the last good file. Returns the
/// bytes written; throws std::runtime_error naming the path and the reason.
std::size_t saveSessionFile(GraphSlam& slam, const std::string& path);
/// The contents of the session file `path`; throws SessionError (missing, a directory, unreadable).
std::string readSessionFile(const std::string& path);

}  // namespace core
}  // namespace mbot
