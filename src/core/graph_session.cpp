// GraphSlam's sessions: saving the graph, loading it, and joining it with new scans (graph_slam.h).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

namespace {

const char kMagic[] = "MBOTSLAM-SESSION\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;
const char kBackend[] = "graph";
// Far more than any building holds; a count beyond these is a damaged file, not a big one.
constexpr uint64_t kMaxNodes = 50000000, kMaxBeams = 100000, kMaxStringBytes = 4096;

// 64-bit FNV-1a: enough to tell a truncated or damaged file from a good one.
uint64_t checksum(const char* data, std::size_t size) {
  uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void putPose(const Eigen::Vector3d& p) {
    for (int i = 0; i < 3; ++i) put<double>(p[i]);
  }
  void putString(const std::string& s) {
    put<uint32_t>(static_cast<uint32_t>(s.size()));
    bytes_ += s;
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class Reader {
 public:
  Reader(const std::string& bytes, std::size_t end) : bytes_(bytes), end_(end) {}
  template <typename T>
  T get(const char* what) {
    if (at_ + sizeof(T) > end_) {
      throw SessionError(std::string("it ends inside ") + what + " (at byte " + std::to_string(at_) + ")");
    }
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  Eigen::Vector3d getPose(const char* what) {
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) p[i] = get<double>(what);
    if (!p.allFinite()) throw SessionError(std::string("a ") + what + " is not finite");
    return p;
  }
  std::string getString(const char* what) {
    const uint32_t n = get<uint32_t>(what);
    if (n > kMaxStringBytes || at_ + n > end_) throw SessionError(std::string("a damaged ") + what);
    std::string s = bytes_.substr(at_, n);
    at_ += n;
    return s;
  }
  uint64_t count(const char* what, uint64_t most) {
    const uint64_t n = get<uint64_t>(what);
    if (n > most) throw SessionError("a damaged count of " + std::string(what) + " (" + std::to_string(n) + ")");
    return n;
  }
  std::size_t at() const { return at_; }
  void skip(std::size_t n) { at_ += n; }

 private:
  const std::string& bytes_;
  std::size_t end_, at_ = 0;
};

bool differs(double a, double b, double tolerance) { return std::abs(a - b) > tolerance; }

}  // namespace

void GraphSlam::saveSession(std::ostream& out) {
  flush();  // every node searched for closures, and solved
  Writer w;
  w.bytes().append(kMagic, kMagicSize);
  w.put<uint32_t>(kSessionVersion);
  w.putString(kBackend);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    w.putPose(params_.matcher.laser_pose);
    w.put<double>(params_.matcher.max_urange);
    w.put<double>(params_.matcher.max_range);
    w.put<double>(params_.delta);
    w.put<double>(travelled_);
    w.put<uint64_t>(nodes_.size());
    for (const Node& n : nodes_) {
      w.putPose(n.pose);
      w.putPose(n.odom);
      w.put<double>(n.time_s);
      w.put<double>(n.travelled_m);
      w.put<uint8_t>(static_cast<uint8_t>((n.redundant ? 1 : 0) | (n.anchor ? 2 : 0) | (n.scan ? 4 : 0)));
      w.put<int32_t>(n.parent);
      w.putPose(n.offset);
      if (n.scan) {
        w.put<double>(n.scan->angle_min_rad);
        w.put<double>(n.scan->angle_increment_rad);
        w.put<double>(n.scan->range_min_m);
        w.put<double>(n.scan->range_max_m);
        w.put<uint64_t>(n.scan->ranges_m.size());
        for (float r : n.scan->ranges_m) w.put<float>(r);
      }
    }
    w.put<uint64_t>(edges_.size());
    for (const PoseGraphEdge& e : edges_) {
      w.put<int32_t>(e.from);
      w.put<int32_t>(e.to);
      w.putPose(e.measurement);
      for (int i = 0; i < 9; ++i) w.put<double>(e.information.data()[i]);
      w.put<uint8_t>(e.robust ? 1 : 0);
    }
    w.put<uint64_t>(submaps_.size());
    for (const Submap& s : submaps_) {
      w.put<int32_t>(s.first);
      w.put<int32_t>(s.last);
    }
    // Every tracked scan's pose, if kept (keep_scan_poses: offline runs), so that a continued run
    // can give the whole trajectory scan by scan.
    w.put<uint64_t>(scans_.size());
    for (const TrackedScan& t : scans_) {
      w.put<double>(t.time_s);
      w.put<int32_t>(t.node);
      w.putPose(t.offset);
    }
  }
  w.put<uint64_t>(checksum(w.bytes().data(), w.bytes().size()));
  out.write(w.bytes().data(), static_cast<std::streamsize>(w.bytes().size()));
}

std::unique_ptr<GraphSlam> GraphSlam::loadSession(const std::string& bytes, const GraphSlamParams& params,
                                                  std::string* notes) {
  if (bytes.size() < kMagicSize || bytes.compare(0, kMagicSize, kMagic) != 0) {
    if (bytes.empty()) throw SessionError("the file is empty");
    if (bytes.find("serialization::archive") != std::string::npos) {
      throw SessionError("it is a Boost archive (slam_toolbox's .posegraph or .data?), not a session of this "
                         "package's slam_gmapping");
    }
    throw SessionError("it is not a session of this package's slam_gmapping (it does not begin with '" +
                       std::string(kMagic, kMagicSize - 1) + "')");
  }
  if (bytes.size() < kMagicSize + sizeof(uint32_t) + sizeof(uint64_t)) throw SessionError("it is truncated");
  uint32_t version;
  std::memcpy(&version, bytes.data() + kMagicSize, sizeof(version));
  if (version != kSessionVersion) {
    throw SessionError("it has format version " + std::to_string(version) + "; this slam_gmapping reads version " +
                       std::to_string(kSessionVersion));
  }
  const std::size_t end = bytes.size() - sizeof(uint64_t);
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + end, sizeof(stored));
  if (stored != checksum(bytes.data(), end)) {
    throw SessionError("it is truncated or damaged (" + std::to_string(bytes.size()) +
                       " bytes; the checksum at its end does not match the rest)");
  }
  Reader r(bytes, end);
  r.skip(kMagicSize + sizeof(uint32_t));  // the magic text and the version, read above
  const std::string backend = r.getString("backend name");
  if (backend != kBackend) {
    throw SessionError("it was saved by the '" + backend + "' backend; sessions are the graph backend's");
  }
  GraphSlamParams p = params;
  const Eigen::Vector3d laser = r.getPose("laser pose");
  const double max_urange = r.get<double>("maxUrange"), max_range = r.get<double>("maxRange");
  const double delta = r.get<double>("resolution");
  std::ostringstream said;
  if (params.matcher.laser_pose.head<2>().norm() > 0.0 || params.matcher.laser_pose.z() != 0.0) {
    if ((params.matcher.laser_pose.head<2>() - laser.head<2>()).norm() > 0.01 ||
        std::abs(normalizeAngle(params.matcher.laser_pose.z() - laser.z())) > 0.01) {
      said << "the laser was at (" << laser.x() << ", " << laser.y() << ", " << laser.z()
           << ") on the base when the session was saved, at (" << params.matcher.laser_pose.x() << ", "
           << params.matcher.laser_pose.y() << ", " << params.matcher.laser_pose.z()
           << ") now: the saved pose is used for every scan. ";
    }
  }
  if (params.matcher.max_urange > 0.0 && differs(params.matcher.max_urange, max_urange, 1e-6)) {
    said << "maxUrange was " << max_urange << " m, now " << params.matcher.max_urange << " m: the saved value is used. ";
  }
  if (differs(params.delta, delta, 1e-9)) {
    said << "the session's map had " << delta << " m cells, now " << params.delta << " m: it is drawn anew at "
         << params.delta << " m. ";
  }
  p.matcher.laser_pose = laser;
  p.matcher.max_urange = max_urange;
  p.matcher.max_range = max_range;
  auto slam = std::make_unique<GraphSlam>(p);
  GraphSlam& g = *slam;
  std::lock_guard<std::mutex> lock(g.mutex_);
  g.travelled_ = r.get<double>("distance travelled");
  const uint64_t n_nodes = r.count("nodes", kMaxNodes);
  g.nodes_.reserve(n_nodes);
  for (uint64_t i = 0; i < n_nodes; ++i) {
    Node n;
    n.pose = r.getPose("node pose");
    n.odom = r.getPose("node odometry");
    n.time_s = r.get<double>("node time");
    n.travelled_m = r.get<double>("node distance");
    const uint8_t flags = r.get<uint8_t>("node flags");
    n.redundant = flags & 1;
    n.anchor = flags & 2;
    n.parent = r.get<int32_t>("node parent");
    if (n.parent < -1 || n.parent >= static_cast<int64_t>(i)) throw SessionError("a node's parent is not a node before it");
    n.offset = r.getPose("node offset");
    if (flags & 4) {
      auto scan = std::make_shared<LaserScan>();
      scan->angle_min_rad = r.get<double>("scan");
      scan->angle_increment_rad = r.get<double>("scan");
      scan->range_min_m = r.get<double>("scan");
      scan->range_max_m = r.get<double>("scan");
      scan->ranges_m.resize(r.count("beams", kMaxBeams));
      for (float& v : scan->ranges_m) v = r.get<float>("scan ranges");
      n.scan = scan;
    }
    g.nodes_.push_back(std::move(n));
  }
  const int count = static_cast<int>(g.nodes_.size());
  const uint64_t n_edges = r.count("edges", 4 * kMaxNodes);
  for (uint64_t i = 0; i < n_edges; ++i) {
    PoseGraphEdge e;
    e.from = r.get<int32_t>("edge");
    e.to = r.get<int32_t>("edge");
    if (e.from < 0 || e.to < 0 || e.from >= count || e.to >= count) throw SessionError("an edge joins nodes it does not hold");
    e.measurement = r.getPose("edge measurement");
    for (int k = 0; k < 9; ++k) e.information.data()[k] = r.get<double>("edge information");
    e.robust = r.get<uint8_t>("edge") != 0;
    g.edges_.push_back(e);
  }
  const uint64_t n_submaps = r.count("submaps", kMaxNodes);
  std::vector<std::pair<int, int>> submaps;
  for (uint64_t i = 0; i < n_submaps; ++i) {
    const int first = r.get<int32_t>("submap"), last = r.get<int32_t>("submap");
    if (first < 0 || last < first || last >= count) throw SessionError("a submap holds nodes the session does not");
    submaps.emplace_back(first, last);
  }
  const uint64_t n_scans = r.count("tracked scans", 100 * kMaxNodes);
  for (uint64_t i = 0; i < n_scans; ++i) {
    TrackedScan t;
    t.time_s = r.get<double>("tracked scan");
    t.node = r.get<int32_t>("tracked scan");
    if (t.node < 0 || t.node >= count) throw SessionError("a tracked scan refers to a node the session does not hold");
    t.offset = r.getPose("tracked scan offset");
    if (p.keep_scan_poses) g.scans_.push_back(t);
  }
  if (r.at() != end) throw SessionError("it holds " + std::to_string(end - r.at()) + " bytes more than its graph");
  if (count == 0) throw SessionError("it holds no nodes");

  // The submaps again, from their nodes' scans (a node whose scan was freed leaves its part out).
  const double reach = g.matchReach();
  for (const auto& [first, last] : submaps) {
    std::vector<Eigen::Vector2d> points;
    auto seen = p.local_visible_only ? std::make_shared<Visibility>() : nullptr;
    const Eigen::Vector3d anchor = g.nodes_[first].pose;
    for (int k = first; k <= last; ++k) {
      const Node& n = g.nodes_[k];
      if (!n.scan) {
        seen.reset();
        continue;
      }
      const Eigen::Vector3d pose = relativePose(anchor, n.pose);
      const std::vector<Eigen::Vector2d> own = matchPoints(*n.scan, p.matcher.laser_pose, reach, p.delta);
      const double c = std::cos(pose.z()), s = std::sin(pose.z());
      for (const auto& q : own) points.emplace_back(pose.x() + c * q.x() - s * q.y(), pose.y() + s * q.x() + c * q.y());
      if (seen) seen->add(*n.scan, p.matcher.laser_pose, pose, reach);
    }
    if (points.empty()) continue;
    g.submaps_.push_back({first, last, std::make_shared<const LikelihoodGrid>(points, p.delta, p.match_sigma), seen});
    ++g.stats_.submaps;
  }
  g.session_start_ = count;
  g.submapped_upto_ = g.released_upto_ = count - 1;
  g.last_closure_travelled_ = g.travelled_;
  g.resume_pending_ = true;
  g.map_dirty_ = true;
  if (notes) *notes = said.str();
  return slam;
}

void GraphSlam::resume(const std::optional<Eigen::Vector3d>& pose, bool localization) {
  std::lock_guard<std::mutex> lock(mutex_);
  resume_pending_ = !nodes_.empty();
  resume_pose_ = pose;
  localization_ = localization;
  resume_failure_.clear();
}

std::string GraphSlam::resumeFailure() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return resume_failure_;
}

bool GraphSlam::resuming() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return resume_pending_;
}

bool GraphSlam::localizing() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return localization_;
}

Eigen::Vector3d GraphSlam::firstPose() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return nodes_.empty() ? Eigen::Vector3d::Zero() : nodes_.front().pose;
}

std::unique_ptr<LikelihoodGrid> GraphSlam::sessionMapNearLocked(const Eigen::Vector3d& pose, Visibility* seen) const {
  const double reach = matchReach();
  std::vector<std::pair<double, int>> near;
  for (int k = 0; k < session_start_; ++k) {
    const double d = (nodes_[k].pose.head<2>() - pose.head<2>()).norm();
    if (nodes_[k].scan && d <= reach) near.emplace_back(d, k);
  }
  const std::size_t wanted = static_cast<std::size_t>(std::max(1, params_.local_map_nodes));
  if (near.size() > wanted) {
    std::nth_element(near.begin(), near.begin() + wanted, near.end());
    near.resize(wanted);
  }
  std::vector<std::pair<Eigen::Vector3d, const LaserScan*>> members;
  for (const auto& [d, k] : near) members.emplace_back(nodes_[k].pose, nodes_[k].scan.get());
  for (const auto& [pose_k, scan_k] : temporary_) members.emplace_back(pose_k, scan_k.get());
  std::vector<Eigen::Vector2d> reference;
  if (seen) seen->clear();
  for (const auto& [at, scan] : members) {
    const std::vector<Eigen::Vector2d> points = surfacePoints(*scan, params_.matcher.laser_pose, reach, params_.delta);
    const double c = std::cos(at.z()), s = std::sin(at.z());
    for (const auto& q : points) reference.emplace_back(at.x() + c * q.x() - s * q.y(), at.y() + s * q.x() + c * q.y());
    if (seen) seen->add(*scan, params_.matcher.laser_pose, at, reach);
  }
  if (reference.empty()) return nullptr;
  return std::make_unique<LikelihoodGrid>(reference, params_.delta, localSigma());
}

bool GraphSlam::resumeWith(const Eigen::Vector3d& odom, const LaserScan& scan, double time_s) {
  const std::vector<Eigen::Vector2d> points = matchPoints(scan, params_.matcher.laser_pose, matchReach(), params_.delta);
  std::optional<Eigen::Vector3d> given;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    given = resume_pose_;
  }
  auto fail = [this](const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex_);
    resume_failure_ = why;
    return false;
  };
  if (points.size() < 10) return fail("the scan has fewer than 10 usable returns");
  std::ostringstream where;
  where.precision(3);
  Eigen::Vector3d found;
  if (given) {
    // Near the pose given: the saved nodes around it, searched within kResumeWindow, kResumeAngle.
    std::unique_ptr<LikelihoodGrid> near;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      near = sessionMapNearLocked(*given, nullptr);
    }
    where << "(" << given->x() << ", " << given->y() << ", " << given->z() << ")";
    if (!near) return fail("no saved node lies within the laser's reach of " + where.str());
    const MatchResult m = matchBranchAndBound(*near, points, *given, {kResumeWindow, kResumeAngle}, 0.0);
    double score = 0.0;
    const Eigen::Vector3d refined = m.found ? refineMatch(*near, points, m.pose, 0.005, 4, &score) : *given;
    if (!m.found || score < params_.local_min_score) {
      std::ostringstream why;
      why << "the scan does not match the saved map within " << kResumeWindow << " m and "
          << kResumeAngle * 180.0 / M_PI << " degrees of " << where.str() << " (best score " << score
          << ", at least " << params_.local_min_score << " needed)";
      return fail(why.str());
    }
    found = refined;
  } else {
    // Anywhere on the saved map, every heading (global matching; branch and bound over the map).
    if (!session_grid_) {
      std::vector<Eigen::Vector2d> reference;
      std::lock_guard<std::mutex> lock(mutex_);
      const double reach = matchReach();
      for (int k = 0; k < session_start_; ++k) {
        const Node& n = nodes_[k];
        if (!n.scan) continue;
        const std::vector<Eigen::Vector2d> own = matchPoints(*n.scan, params_.matcher.laser_pose, reach, params_.delta);
        const double c = std::cos(n.pose.z()), s = std::sin(n.pose.z());
        for (const auto& q : own) reference.emplace_back(n.pose.x() + c * q.x() - s * q.y(), n.pose.y() + s * q.x() + c * q.y());
      }
      if (reference.empty()) return fail("the session holds no scans to match against");
      session_grid_ = std::make_unique<LikelihoodGrid>(reference, params_.delta, params_.match_sigma);
    }
    const LikelihoodGrid& grid = *session_grid_;
    const Eigen::Vector2d half(0.5 * grid.width() * grid.resolution(), 0.5 * grid.height() * grid.resolution());
    const Eigen::Vector3d centre(grid.origin().x() + half.x(), grid.origin().y() + half.y(), 0.0);
    const MatchWindow window{half.maxCoeff(), M_PI};
    const MatchResult best = matchBranchAndBound(grid, points, centre, window, params_.loop_min_response);
    if (!best.found) {
      std::ostringstream why;
      why << "the scan matches nowhere on the saved map (searched all of it, every heading; no pose scores "
          << params_.loop_min_response << " or more): give the start pose (~map_start_pose, or "
          << "~map_start_at_dock if the robot stands where the session began)";
      return fail(why.str());
    }
    const MatchResult second = matchBranchAndBound(grid, points, centre, window, params_.loop_ambiguity * best.score,
                                                   &best.pose, 0.5, 0.2);
    if (second.found) {
      std::ostringstream why;
      why << "the scan matches the saved map nearly as well at (" << best.pose.x() << ", " << best.pose.y() << ", "
          << best.pose.z() << ") and at (" << second.pose.x() << ", " << second.pose.y() << ", " << second.pose.z()
          << "): give the start pose (~map_start_pose or ~map_start_at_dock), or move the robot where the view "
          << "is not repeated";
      return fail(why.str());
    }
    double score = 0.0;
    found = refineMatch(grid, points, best.pose, 0.005, 4, &score);
  }
  session_grid_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  resume_failure_.clear();
  resume_pending_ = false;
  last_odom_ = track_odom_ = odom;
  linear_distance_ = angular_distance_ = 0.0;
  last_update_time_ = time_s;
  if (localization_) {
    temporary_.clear();
    temporary_.emplace_back(found, std::make_shared<const LaserScan>(scan));
    local_map_ = sessionMapNearLocked(found, &local_seen_);
    local_anchor_ = nodes_.back().pose;  // currentPose(): the last node composed with the track since it
    track_pose_ = found;
    localized_at_ = found;
    if (params_.keep_scan_poses) scans_.push_back({time_s, session_start_ - 1, relativePose(local_anchor_, found)});
    return false;
  }
  // The first node of the new part, joined to the nearest saved node by the match.
  int nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < session_start_; ++k) {
    const double d = (nodes_[k].pose.head<2>() - found.head<2>()).norm();
    if (nodes_[k].parent < 0 && d < best) {
      best = d;
      nearest = k;
    }
  }
  const int index = static_cast<int>(nodes_.size());
  session_start_ = index;
  edges_.push_back({nearest, index, relativePose(nodes_[nearest].pose, found), edgeInformation(1.0), false});
  auto shared_points = std::make_shared<const std::vector<Eigen::Vector2d>>(points);
  nodes_.push_back({found, odom, time_s, travelled_, std::make_shared<const LaserScan>(scan), shared_points, false});
  if (params_.keep_scan_poses) scans_.push_back({time_s, index, Eigen::Vector3d::Zero()});
  if (params_.closures) {
    pending_.push_back(index);
  } else {
    submapped_upto_ = index;
  }
  rebuildLocalMapLocked();
  if (params_.background) work_cv_.notify_one();
  return true;
}

bool GraphSlam::localize(const Eigen::Vector3d& odom, const LaserScan& scan, double time_s) {
  Eigen::Vector3d predicted;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const Eigen::Vector3d step = relativePose(track_odom_, odom);
    predicted = composePose(track_pose_, step);
    if (step.head<2>().norm() < kLocalizeStep && std::abs(step.z()) < kLocalizeTurn) {
      // As amcl's update_min_d and update_min_a: odometry carries the pose over short moves (and
      // a robot standing still costs nothing); currentPose() composes it.
      last_odom_ = odom;
      if (params_.keep_scan_poses) scans_.push_back({time_s, session_start_ - 1, relativePose(local_anchor_, predicted)});
      return false;
    }
  }
  std::vector<Eigen::Vector2d> points = matchPoints(scan, params_.matcher.laser_pose, matchReach(), params_.delta);
  if (params_.local_visible_only && !local_seen_.empty()) {
    std::vector<Eigen::Vector2d> seen = local_seen_.seenOf(points, predicted, params_.delta, nullptr);
    if (2 * seen.size() >= points.size()) points.swap(seen);
  }
  const Eigen::Vector3d tracked = matchLocally(predicted, points);
  std::lock_guard<std::mutex> lock(mutex_);
  last_odom_ = track_odom_ = odom;
  track_pose_ = tracked;
  if (params_.keep_scan_poses) {
    scans_.push_back({time_s, session_start_ - 1, relativePose(local_anchor_, tracked)});
  }
  if ((tracked.head<2>() - localized_at_.head<2>()).norm() > kLocalizeRebuild) {
    // slam_toolbox's rolling window: the last few scans as temporary nodes beside the saved nodes
    // nearest the robot, so that it is tracked also against what it has just seen (where the
    // session saw a room only from its door, the saved nodes alone lost the track on FR079), and
    // the local map is built again around it. Nothing is added to the graph.
    temporary_.emplace_back(tracked, std::make_shared<const LaserScan>(scan));
    if (temporary_.size() > kTemporaryNodes) temporary_.pop_front();
    local_map_ = sessionMapNearLocked(tracked, &local_seen_);
    localized_at_ = tracked;
  }
  return false;
}

std::string sessionPath(const std::string& filename) {
  std::string path = filename;
  if (!path.empty() && path[0] == '~') {
    const char* home = std::getenv("HOME");
    path = std::string(home ? home : "") + path.substr(1);
  }
  const std::string ext = ".posegraph";
  if (path.size() < ext.size() || path.compare(path.size() - ext.size(), ext.size(), ext) != 0) path += ext;
  return path;
}

std::size_t saveSessionFile(GraphSlam& slam, const std::string& path) {
  std::ostringstream out;
  slam.saveSession(out);
  const std::string bytes = out.str();
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error("cannot write " + tmp + ": " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write " + tmp + ": " + why);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot replace " + path + ": " + why);
  }
  return bytes.size();
}

std::string readSessionFile(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw SessionError("no such file");
  if (S_ISDIR(st.st_mode)) throw SessionError("it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SessionError(std::string("it cannot be read: ") + std::strerror(errno));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

}  // namespace core
}  // namespace mbot
