#include "mbot_slam_navigation/core/correlative_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "mbot_slam_navigation/core/cell.h"
#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

LikelihoodGrid::LikelihoodGrid(const std::vector<Eigen::Vector2d>& points, double resolution_m, double sigma_m)
    : resolution_(resolution_m) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("LikelihoodGrid: resolution must be positive, got " + std::to_string(resolution_m));
  }
  if (!(sigma_m > 0.0) || !std::isfinite(sigma_m)) {
    throw std::invalid_argument("LikelihoodGrid: sigma must be positive, got " + std::to_string(sigma_m));
  }
  const int r = static_cast<int>(std::ceil(3.0 * sigma_m / resolution_m));
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();
  if (!points.empty()) {
    lo = hi = points.front();
    for (const auto& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // Whole cells, so that grids built from the same frame share cell boundaries.
  origin_ = ((lo / resolution_).array().floor() - (r + 1)).matrix() * resolution_;
  width_ = static_cast<int>(std::ceil((hi.x() - origin_.x()) / resolution_)) + r + 2;
  height_ = static_cast<int>(std::ceil((hi.y() - origin_.y()) / resolution_)) + r + 2;
  cells_.assign(static_cast<std::size_t>(width_) * height_, 0);
  const double inv_two_sigma2 = 1.0 / (2.0 * sigma_m * sigma_m);
  // The kernel is separable, exp(-(dx^2 + dy^2) k) = exp(-dx^2 k) exp(-dy^2 k): 2 (2r + 1)
  // exponentials a point rather than (2r + 1)^2 (they were a fifth of the tracking's time).
  std::vector<double> kx(2 * r + 1), ky(2 * r + 1);
  for (const auto& p : points) {
    const Cell c = worldToCell(origin_, resolution_, p);
    const Eigen::Vector2d d0 = cellCenter(origin_, resolution_, c) - p;
    for (int i = -r; i <= r; ++i) {
      const double dx = d0.x() + i * resolution_, dy = d0.y() + i * resolution_;
      kx[i + r] = std::exp(-dx * dx * inv_two_sigma2);
      ky[i + r] = kMax * std::exp(-dy * dy * inv_two_sigma2);
    }
    for (int dy = -r; dy <= r; ++dy) {
      const int y = c.y + dy;
      if (y < 0 || y >= height_) continue;
      Value* row = &cells_[static_cast<std::size_t>(y) * width_];
      for (int dx = -r; dx <= r; ++dx) {
        const int x = c.x + dx;
        if (x < 0 || x >= width_) continue;
        const auto v = static_cast<Value>(ky[dy + r] * kx[dx + r] + 0.5);  // rounded; both factors >= 0
        row[x] = std::max(row[x], v);
      }
    }
  }
}

namespace {
// Catmull-Rom weights of the four samples around t in [0, 1) (cubic convolution, a = -0.5).
inline void cubicWeights(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = -0.5 * t3 + t2 - 0.5 * t;
  w[1] = 1.5 * t3 - 2.5 * t2 + 1.0;
  w[2] = -1.5 * t3 + 2.0 * t2 + 0.5 * t;
  w[3] = 0.5 * t3 - 0.5 * t2;
}
}  // namespace

double LikelihoodGrid::interpolated(const Eigen::Vector2d& p) const {
  // Bicubic, not bilinear: between two cells of equal value (a wall on the border between them)
  // bilinear interpolation is flat, so a scan could sit anywhere within half a cell of the wall at
  // no cost (a gtest corridor's tracked pose wandered 2.5 cm off that way). Cubic convolution
  // peaks where the wall is, as Cartographer's scan matcher interpolates.
  const double fx = (p.x() - origin_.x()) / resolution_ - 0.5, fy = (p.y() - origin_.y()) / resolution_ - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  double wx[4], wy[4];
  cubicWeights(fx - x0, wx);
  cubicWeights(fy - y0, wy);
  double v = 0.0;
  if (x0 >= 1 && y0 >= 1 && x0 + 2 < width_ && y0 + 2 < height_) {  // all 16 samples inside: no checks
    const Value* p = &cells_[static_cast<std::size_t>(y0 - 1) * width_ + (x0 - 1)];
    for (int j = 0; j < 4; ++j, p += width_) v += wy[j] * (wx[0] * p[0] + wx[1] * p[1] + wx[2] * p[2] + wx[3] * p[3]);
    return v / kMax;
  }
  for (int j = 0; j < 4; ++j) {
    double row = 0.0;
    for (int i = 0; i < 4; ++i) row += wx[i] * value(x0 - 1 + i, y0 - 1 + j);
    v += wy[j] * row;
  }
  return v / kMax;
}

double LikelihoodGrid::score(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector3d& pose) const {
  if (points.empty()) return 0.0;
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  double sum = 0.0;
  for (const auto& p : points) {
    sum += interpolated({pose.x() + c * p.x() - s * p.y(), pose.y() + s * p.x() + c * p.y()});
  }
  return sum / static_cast<double>(points.size());
}

void LikelihoodGrid::buildLevels(int levels) const {
  for (int h = static_cast<int>(levels_.size()) + 1; h < levels; ++h) {
    // max over [x, x + 2^h) = max of the two halves [x, x + s) and [x + s, x + 2s), s = 2^(h-1),
    // in x (into `across`), then in y. With pad = 2^h - 1 and the level below's pad' = pad - s,
    // the value at stored column x takes the below's stored columns x - s and x (rows likewise).
    const Level below = level(h - 1);
    const int s = 1 << (h - 1);
    const int w = below.width + s, rows = below.height + s;
    std::vector<Value> across(static_cast<std::size_t>(w) * below.height);
    for (int y = 0; y < below.height; ++y) {
      const Value* in = below.data + static_cast<std::size_t>(y) * below.width;
      Value* out = &across[static_cast<std::size_t>(y) * w];
      for (int x = 0; x < w; ++x) out[x] = std::max(x >= s ? in[x - s] : Value(0), x < below.width ? in[x] : Value(0));
    }
    std::vector<Value> out(static_cast<std::size_t>(w) * rows);
    for (int y = 0; y < rows; ++y) {
      const Value* a = y >= s ? &across[static_cast<std::size_t>(y - s) * w] : nullptr;
      const Value* b = y < below.height ? &across[static_cast<std::size_t>(y) * w] : nullptr;
      Value* o = &out[static_cast<std::size_t>(y) * w];
      for (int x = 0; x < w; ++x) o[x] = std::max(a ? a[x] : Value(0), b ? b[x] : Value(0));
    }
    levels_.push_back(std::move(out));
  }
}

void LikelihoodGrid::dropLevels() const { std::vector<std::vector<Value>>().swap(levels_); }

std::size_t LikelihoodGrid::bytes() const {
  std::size_t n = cells_.size();
  for (const auto& l : levels_) n += l.size();
  return n * sizeof(Value);
}

namespace {
// One point per voxel_m square: the voxel's key, for a set of the voxels taken.
uint64_t voxelKey(const Eigen::Vector2d& p, double voxel_m) {
  const int64_t kx = static_cast<int64_t>(std::floor(p.x() / voxel_m)), ky = static_cast<int64_t>(std::floor(p.y() / voxel_m));
  return (static_cast<uint64_t>(kx) << 32) ^ (static_cast<uint64_t>(ky) & 0xffffffffu);
}

// Calls f(i, r, p) for every beam i with a usable return r (finite, within [range_min,
// min(max_range, range_max))), p its end point in the base frame.
template <typename F>
void forEachReturn(const LaserScan& scan, const Eigen::Vector3d& laser_pose, double max_range_m, F f) {
  const double limit = scan.usableRange(max_range_m);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r <= 0.0 || r < scan.range_min_m || r >= limit) continue;
    const double a = laser_pose.z() + scan.beamAngle(i);
    f(i, r, Eigen::Vector2d(laser_pose.head<2>() + r * Eigen::Vector2d(std::cos(a), std::sin(a))));
  }
}
}  // namespace

std::vector<Eigen::Vector2d> matchPoints(const LaserScan& scan, const Eigen::Vector3d& laser_pose, double max_range_m,
                                         double voxel_m) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(scan.ranges_m.size());
  std::unordered_set<uint64_t> seen;
  forEachReturn(scan, laser_pose, max_range_m, [&](std::size_t, double, const Eigen::Vector2d& p) {
    if (voxel_m <= 0.0 || seen.insert(voxelKey(p, voxel_m)).second) out.push_back(p);
  });
  return out;
}

std::vector<Eigen::Vector2d> surfacePoints(const LaserScan& scan, const Eigen::Vector3d& laser_pose, double max_range_m,
                                           double voxel_m) {
  if (!(voxel_m > 0.0)) return matchPoints(scan, laser_pose, max_range_m, voxel_m);
  std::vector<Eigen::Vector2d> out;
  out.reserve(2 * scan.ranges_m.size());
  std::unordered_set<uint64_t> seen;
  auto add = [&](const Eigen::Vector2d& p) {
    if (seen.insert(voxelKey(p, voxel_m)).second) out.push_back(p);
  };
  const double step = std::abs(scan.angle_increment_rad);
  std::size_t last_i = 0;
  bool have_last = false;
  Eigen::Vector2d last;
  double last_r = 0.0;
  forEachReturn(scan, laser_pose, max_range_m, [&](std::size_t i, double r, const Eigen::Vector2d& p) {
    // only neighbouring beams make a surface
    if (have_last && i == last_i + 1) {
      const double gap = (p - last).norm();
      const double max_gap = std::min(0.3, std::max(2.0 * voxel_m, 4.0 * std::max(r, last_r) * step));
      if (gap > voxel_m && gap <= max_gap) {
        const int n = static_cast<int>(gap / voxel_m);
        for (int k = 1; k <= n; ++k) add(last + (p - last) * (static_cast<double>(k) / (n + 1)));
      }
    }
    add(p);
    last = p;
    last_r = r;
    last_i = i;
    have_last = true;
  });
  return out;
}

void Visibility::add(const LaserScan& scan, const Eigen::Vector3d& laser_pose, const Eigen::Vector3d& pose,
                     double max_range_m) {
  View v;
  const Eigen::Vector3d laser = composePose(pose, laser_pose);
  v.origin = laser.head<2>();
  v.first_angle = laser.z() + scan.angle_min_rad;
  v.increment = scan.angle_increment_rad;
  v.all_round = scan.seesAllRound();
  const double limit = scan.usableRange(max_range_m);
  v.reach.reserve(scan.ranges_m.size());
  for (float r : scan.ranges_m) {
    // No return (inf, or at the sensor's maximum: REP 117) means free out to the maximum range;
    // NaN, -inf and returns below range_min say nothing.
    if (std::isnan(r) || r < scan.range_min_m || r <= 0.0f) {
      v.reach.push_back(0.0f);
    } else {
      v.reach.push_back(static_cast<float>(std::min<double>(r, limit)));
    }
  }
  if (v.increment != 0.0 && !v.reach.empty()) views_.push_back(std::move(v));
}

bool Visibility::seen(const Eigen::Vector2d& p, double tolerance_m, const Eigen::Vector2d* normal) const {
  for (const View& v : views_) {
    const Eigen::Vector2d d = p - v.origin;
    // A scan behind the surface (the other face of a wall) did not see this side of it.
    if (normal && d.dot(*normal) >= 0.0) continue;
    const double rho = d.norm();
    const int n = static_cast<int>(v.reach.size());
    // bearing relative to beam 0, in [0, 2 pi) along the direction the beams advance
    double rel = std::atan2(d.y(), d.x()) - v.first_angle;
    if (v.increment < 0.0) rel = -rel;
    rel -= 2.0 * M_PI * std::floor(rel / (2.0 * M_PI));
    // The nearest beam: at a depth edge (a door jamb before a room) the farther of the two beams
    // either side would let through what lies just behind the jamb, which that scan did not see.
    int b = static_cast<int>(std::lround(rel / std::abs(v.increment)));
    if (b >= n) {
      if (!v.all_round) continue;  // outside the field of view
      b = b == n ? 0 : n - 1;
    }
    if (rho <= v.reach[b] + tolerance_m) return true;
  }
  return false;
}

std::vector<Eigen::Vector2d> Visibility::seenOf(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector3d& pose,
                                               double tolerance_m, const std::vector<Eigen::Vector2d>* normals) const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(points.size());
  const Eigen::Rotation2Dd turn(pose.z());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d& p = points[i];
    const bool has_side = normals && !(*normals)[i].isZero();
    const Eigen::Vector2d side = has_side ? Eigen::Vector2d(turn * (*normals)[i]) : Eigen::Vector2d::Zero();  // reference frame
    if (seen(pose.head<2>() + turn * p, tolerance_m, has_side ? &side : nullptr)) out.push_back(p);
  }
  return out;
}

std::vector<Eigen::Vector2d> Visibility::notBehindOf(const std::vector<Eigen::Vector2d>& points,
                                                    const Eigen::Vector3d& pose, double tolerance_m, double behind_m,
                                                    const std::vector<Eigen::Vector2d>& normals) const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(points.size());
  const Eigen::Rotation2Dd turn(pose.z());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d& p = points[i];
    if (i < normals.size() && !normals[i].isZero()) {
      const Eigen::Vector2d w = pose.head<2>() + turn * p;  // reference frame, as in seenOf
      const Eigen::Vector2d side = turn * normals[i];
      const Eigen::Vector2d back = -side;
      if (!seen(w, tolerance_m, &side) && seen(w, behind_m, &back)) continue;
    }
    out.push_back(p);
  }
  return out;
}

std::vector<Eigen::Vector2d> surfaceNormals(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& origin,
                                            double max_gap_m) {
  std::vector<Eigen::Vector2d> out(points.size(), Eigen::Vector2d::Zero());
  for (std::size_t i = 1; i + 1 < points.size(); ++i) {
    const Eigen::Vector2d& a = points[i - 1];
    const Eigen::Vector2d& b = points[i + 1];
    // Both neighbours on the same surface, or the point is an edge and its side is not known.
    if ((a - points[i]).norm() > max_gap_m || (b - points[i]).norm() > max_gap_m) continue;
    const Eigen::Vector2d t = b - a;
    if (t.norm() < 1e-9) continue;
    Eigen::Vector2d n(-t.y(), t.x());
    n.normalize();
    if (n.dot(origin - points[i]) < 0.0) n = -n;  // towards the laser that saw it
    out[i] = n;
  }
  return out;
}

namespace {
struct Candidate {
  int rotation;
  int ox, oy;  // translation offset [cells]
  int64_t score;  // sum of (pooled) values
};

class BranchAndBound {
 public:
  BranchAndBound(const LikelihoodGrid& grid, int window_cells, const std::vector<std::vector<Cell>>& rotated)
      : grid_(grid), wl_(window_cells), rotated_(rotated) {}

  int64_t scoreAt(const Candidate& c, int level) const {
    const LikelihoodGrid::Level l = grid_.level(level);
    int64_t sum = 0;
    for (const Cell& p : rotated_[c.rotation]) sum += l.at(p.x + c.ox, p.y + c.oy);
    return sum;
  }

  // Depth first, best bound first; `best` is raised by every leaf that beats it, and a block whose
  // bound does not beat it is never opened (its children can only score lower).
  template <typename Accept>
  void search(std::vector<Candidate>& candidates, int level, Candidate* best, const Accept& accept) const {
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    for (const Candidate& c : candidates) {
      if (c.score <= best->score) return;  // sorted: nothing after this can beat it either
      if (level == 0) {
        if (!accept(c)) continue;
        *best = c;
        return;
      }
      const int half = 1 << (level - 1);
      std::vector<Candidate> children;
      children.reserve(4);
      for (int dx : {0, half}) {
        for (int dy : {0, half}) {
          Candidate child{c.rotation, c.ox + dx, c.oy + dy, 0};
          if (child.ox > wl_ || child.oy > wl_) continue;
          child.score = scoreAt(child, level - 1);
          children.push_back(child);
        }
      }
      search(children, level - 1, best, accept);
    }
  }

 private:
  const LikelihoodGrid& grid_;
  int wl_;
  const std::vector<std::vector<Cell>>& rotated_;
};
}  // namespace

MatchResult matchBranchAndBound(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                                const Eigen::Vector3d& init, const MatchWindow& window, double min_score,
                                const Eigen::Vector3d* exclude, double exclude_radius_m, double exclude_angle_rad) {
  MatchResult result;
  if (points.empty()) return result;
  const double res = grid.resolution();
  double dmax = 0.0;
  for (const auto& p : points) dmax = std::max(dmax, p.norm());
  // The angle that moves the farthest point by one cell (law of cosines).
  const double astep = dmax > res ? std::acos(1.0 - res * res / (2.0 * dmax * dmax)) : std::max(window.angular_rad, 1e-3);
  const int na = window.angular_rad > 0.0 ? static_cast<int>(std::ceil(window.angular_rad / astep)) : 0;
  const int wl = std::max(0, static_cast<int>(std::ceil(window.linear_m / res)));
  int top = 0;
  while ((1 << top) < 2 * wl + 1 && top < 7) ++top;
  grid.buildLevels(top + 1);

  std::vector<std::vector<Cell>> rotated(2 * na + 1);
  std::vector<double> angles(2 * na + 1);
  for (int k = -na; k <= na; ++k) {
    const double yaw = init.z() + k * astep;
    angles[k + na] = yaw;
    const double c = std::cos(yaw), s = std::sin(yaw);
    auto& cells = rotated[k + na];
    cells.reserve(points.size());
    for (const auto& p : points) {
      cells.push_back(worldToCell(grid.origin(), res, {init.x() + c * p.x() - s * p.y(), init.y() + s * p.x() + c * p.y()}));
    }
  }
  const BranchAndBound bb(grid, wl, rotated);
  std::vector<Candidate> candidates;
  const int stride = 1 << top;
  for (int r = 0; r <= 2 * na; ++r) {
    for (int ox = -wl; ox <= wl; ox += stride) {
      for (int oy = -wl; oy <= wl; oy += stride) {
        Candidate c{r, ox, oy, 0};
        c.score = bb.scoreAt(c, top);
        candidates.push_back(c);
      }
    }
  }
  const double norm = LikelihoodGrid::kMax * static_cast<double>(points.size());
  auto poseOf = [&](const Candidate& c) {
    return Eigen::Vector3d(init.x() + c.ox * res, init.y() + c.oy * res, normalizeAngle(angles[c.rotation]));
  };
  auto accept = [&](const Candidate& c) {
    if (!exclude) return true;
    const Eigen::Vector3d p = poseOf(c);
    return (p.head<2>() - exclude->head<2>()).norm() > exclude_radius_m ||
           std::abs(normalizeAngle(p.z() - exclude->z())) > exclude_angle_rad;
  };
  // Leaves must beat min_score; scores are integers, so start just below it.
  Candidate best{0, 0, 0, static_cast<int64_t>(std::ceil(min_score * norm)) - 1};
  bb.search(candidates, top, &best, accept);
  if (best.score < static_cast<int64_t>(std::ceil(min_score * norm)) || best.score <= 0) return result;
  result.found = true;
  result.pose = poseOf(best);
  result.score = best.score / norm;
  return result;
}

Eigen::Vector3d refineMatch(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                            const Eigen::Vector3d& init, double angular_step_rad, int halvings, double* score,
                            double prior_weight) {
  Eigen::Vector3d current = init;
  auto objective = [&](const Eigen::Vector3d& p, double* plain) {
    *plain = grid.score(points, p);
    return *plain - prior_weight * (p.head<2>() - init.head<2>()).squaredNorm();
  };
  double plain = 0.0;
  double best = objective(current, &plain);
  double best_plain = plain;
  double l = 0.5 * grid.resolution(), a = angular_step_rad;
  static const double kMoves[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int round = 0; round <= halvings;) {
    bool improved = false;
    for (const auto& m : kMoves) {
      const Eigen::Vector3d c(current.x() + m[0] * l, current.y() + m[1] * l, normalizeAngle(current.z() + m[2] * a));
      const double s = objective(c, &plain);
      if (s > best) {
        best = s;
        best_plain = plain;
        current = c;
        improved = true;
      }
    }
    if (!improved) {
      l *= 0.5;
      a *= 0.5;
      ++round;
    }
  }
  if (score) *score = best_plain;
  return current;
}

Eigen::Matrix3d scoreCurvature(const LikelihoodGrid& grid, const std::vector<Eigen::Vector2d>& points,
                               const Eigen::Vector3d& pose) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  if (points.empty()) return h;
  double range = 0.0;
  for (const auto& p : points) range += p.norm();
  range /= static_cast<double>(points.size());
  const double hl = 0.5 * grid.resolution();
  const Eigen::Vector3d step(hl, hl, hl / std::max(range, grid.resolution()));
  auto at = [&](const Eigen::Vector3d& d) { return grid.score(points, pose + d); };
  const double s0 = at(Eigen::Vector3d::Zero());
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d di = Eigen::Vector3d::Zero();
    di[i] = step[i];
    h(i, i) = -(at(di) - 2.0 * s0 + at(-di)) / (step[i] * step[i]);
    for (int j = i + 1; j < 3; ++j) {
      Eigen::Vector3d dj = Eigen::Vector3d::Zero();
      dj[j] = step[j];
      h(i, j) = h(j, i) = -(at(di + dj) - at(di - dj) - at(dj - di) + at(-di - dj)) / (4.0 * step[i] * step[j]);
    }
  }
  // A pose off the peak (a climb stopped on a slope) may give a saddle: what does not curve down
  // constrains nothing.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(h);
  const Eigen::Vector3d lambda = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
}

MatchDirections matchDirections(const Eigen::Matrix3d& curvature, const std::vector<Eigen::Vector2d>& points) {
  MatchDirections d;
  if (!points.empty()) {
    double range = 0.0;
    for (const auto& p : points) range += p.norm();
    d.range_m = std::max(range / static_cast<double>(points.size()), 1e-3);
  }
  const Eigen::DiagonalMatrix<double, 3> unscale(1.0, 1.0, 1.0 / d.range_m);
  const Eigen::Matrix3d scaled = unscale * curvature * unscale;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scaled);
  d.vectors = eig.eigenvectors();
  d.values = eig.eigenvalues().cwiseMax(0.0);
  return d;
}

Eigen::Vector3d MatchDirections::scaled(const Eigen::Vector3d& delta) const {
  return {delta.x(), delta.y(), range_m * delta.z()};
}

Eigen::Vector3d MatchDirections::weighOpen(const Eigen::Vector3d& delta, double min_curvature,
                                           double prior_curvature) const {
  const Eigen::Vector3d s = scaled(delta);
  Eigen::Vector3d kept = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const double share =
        values[k] >= min_curvature ? 1.0 : values[k] / std::max(values[k] + std::max(prior_curvature, 0.0), 1e-12);
    kept += share * vectors.col(k) * vectors.col(k).dot(s);
  }
  return {kept.x(), kept.y(), kept.z() / range_m};
}

}  // namespace core
}  // namespace mbot
