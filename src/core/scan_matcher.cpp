#include "mbot_slam_navigation/core/scan_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

void ScanMatcherParams::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string(name) + " must be positive, got " + std::to_string(v));
  };
  positive(sigma, "sigma");
  positive(lstep, "lstep");
  positive(astep, "astep");
  positive(lsigma, "lsigma");
  positive(max_urange, "maxUrange");
  positive(max_range, "maxRange");
  if (kernel_size < 0) throw std::invalid_argument("kernelSize must be >= 0");
  if (iterations < 0) throw std::invalid_argument("iterations must be >= 0");
  if (lskip < 0) throw std::invalid_argument("lskip must be >= 0");
}

ScanMatcher::ScanMatcher(const ScanMatcherParams& params, double resolution_m) : params_(params), resolution_(resolution_m) {
  params_.validate();
}

PreparedScan ScanMatcher::prepare(const LaserScan& scan) const {
  PreparedScan out;
  const double back = std::sqrt(2.0) * resolution_;
  out.hit.reserve(scan.ranges_m.size());
  out.free.reserve(scan.ranges_m.size());
  for (std::size_t i = 0; i < scan.ranges_m.size(); i += params_.lskip + 1) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r >= params_.max_range || r > params_.max_urange || r <= 0.0) continue;
    const double a = params_.laser_pose.z() + scan.beamAngle(i);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    const Eigen::Vector2d origin = params_.laser_pose.head<2>();
    out.hit.push_back(origin + r * dir);
    out.free.push_back(origin + (r - back) * dir);
  }
  return out;
}

void ScanMatcher::likelihoodAndScore(const SlamGrid& map, const Eigen::Vector3d& pose, const PreparedScan& scan,
                                     double* score, double* log_likelihood, int* matched) const {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  const double inv_sigma = 1.0 / params_.sigma, inv_lsigma = 1.0 / params_.lsigma;
  const double no_hit = params_.null_likelihood * inv_lsigma;
  const int k = params_.kernel_size;
  const Eigen::Vector2d origin = map.origin();
  const double res = map.resolution();
  double sc = 0.0, ll = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < scan.hit.size(); ++i) {
    const Eigen::Vector2d& h = scan.hit[i];
    const Eigen::Vector2d& f = scan.free[i];
    const Eigen::Vector2d phit(pose.x() + c * h.x() - s * h.y(), pose.y() + s * h.x() + c * h.y());
    const Eigen::Vector2d pfree(pose.x() + c * f.x() - s * f.y(), pose.y() + s * f.x() + c * f.y());
    const Cell ihit = map.worldToCell(phit);
    const Cell ifree = map.worldToCell(pfree);
    const int fdx = ifree.x - ihit.x, fdy = ifree.y - ihit.y;
    double best = std::numeric_limits<double>::infinity();
    // A candidate: occupied, and the cell one step back along the beam is not.
    auto consider = [&](const HitCell& cell, const Cell& cc) {
      // hits > threshold * visits, i.e. occupancy above the threshold, without a division
      if (cell.visits == 0 || cell.hits <= params_.fullness_threshold * cell.visits) return;
      const HitCell& fcell = map.cell({cc.x + fdx, cc.y + fdy});
      if (fcell.visits > 0 && fcell.hits >= params_.fullness_threshold * fcell.visits) return;
      const double inv = 1.0 / cell.hits;
      const double mx = origin.x() + (cc.x + 0.5) * res + cell.acc_x * inv;
      const double my = origin.y() + (cc.y + 0.5) * res + cell.acc_y * inv;
      best = std::min(best, (phit.x() - mx) * (phit.x() - mx) + (phit.y() - my) * (phit.y() - my));
    };
    const int lx = ihit.x & (SlamGrid::kPatchSize - 1), ly = ihit.y & (SlamGrid::kPatchSize - 1);
    if (ihit.x >= 0 && ihit.y >= 0 && lx >= k && ly >= k && lx + k < SlamGrid::kPatchSize && ly + k < SlamGrid::kPatchSize) {
      // The window lies in one patch (most beams): read it from there, and skip the beam at once
      // when that patch was never written. This loop is most of the particle filter's time.
      const HitCell* cells = map.patchCells(ihit.x >> SlamGrid::kPatchBits, ihit.y >> SlamGrid::kPatchBits);
      if (cells) {
        for (int dy = -k; dy <= k; ++dy) {  // rows outermost: a row's cells lie side by side
          for (int dx = -k; dx <= k; ++dx) {
            consider(cells[((ly + dy) << SlamGrid::kPatchBits) | (lx + dx)], Cell{ihit.x + dx, ihit.y + dy});
          }
        }
      }
    } else {
      for (int dx = -k; dx <= k; ++dx) {
        for (int dy = -k; dy <= k; ++dy) {
          const Cell cc{ihit.x + dx, ihit.y + dy};
          consider(map.cell(cc), cc);
        }
      }
    }
    if (std::isfinite(best)) {
      sc += std::exp(-best * inv_sigma);
      ll += -best * inv_lsigma;
      ++n;
    } else {
      ll += no_hit;
    }
  }
  *score = sc;
  *log_likelihood = ll;
  if (matched) *matched = n;
}

double ScanMatcher::score(const SlamGrid& map, const Eigen::Vector3d& pose, const PreparedScan& scan) const {
  double s, l;
  likelihoodAndScore(map, pose, scan, &s, &l);
  return s;
}

Eigen::Vector3d ScanMatcher::optimize(const SlamGrid& map, const Eigen::Vector3d& init, const PreparedScan& scan,
                                      double* best_score) const {
  Eigen::Vector3d current = init;
  double current_score = score(map, current, scan);
  double ldelta = params_.lstep, adelta = params_.astep;
  double best = -1.0;
  int refinement = 0;
  static const double kMoves[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}};
  do {
    if (best >= current_score) {
      ++refinement;
      ldelta *= 0.5;
      adelta *= 0.5;
    }
    best = current_score;
    Eigen::Vector3d best_local = current;
    for (const auto& m : kMoves) {
      const Eigen::Vector3d candidate(current.x() + m[0] * ldelta, current.y() + m[1] * ldelta,
                                      normalizeAngle(current.z() + m[2] * adelta));
      const double sc = score(map, candidate, scan);
      if (sc > current_score) {
        current_score = sc;
        best_local = candidate;
      }
    }
    current = best_local;
  } while (current_score > best || refinement < params_.iterations);
  *best_score = best;
  return current;
}

void ScanMatcher::registerScan(SlamGrid& map, const Eigen::Vector3d& pose, const LaserScan& scan) const {
  const Eigen::Vector3d laser = composePose(pose, params_.laser_pose);
  const Eigen::Vector2d from = laser.head<2>();
  const double clear_on_no_return = std::min(params_.max_urange, scan.range_max_m);
  // End points first, so that the map grows to what this scan reaches and no further: every
  // particle's patch table is copied at resampling, so its size is on the hot path.
  std::vector<std::pair<Eigen::Vector2d, bool>> beams;
  beams.reserve(scan.ranges_m.size());
  Eigen::Vector2d lo = from, hi = from;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    double r = scan.ranges_m[i];
    if (std::isnan(r) || r < scan.range_min_m || r <= 0.0) continue;
    bool hit = true;
    if (std::isinf(r)) {
      r = clear_on_no_return;  // REP 117: nothing within range_max, as far as we trust the sensor
      hit = false;
    } else if (r >= params_.max_range) {
      continue;  // gmapping: a reading at or beyond maxRange says nothing (no echo, glass)
    } else if (r > params_.max_urange) {
      r = params_.max_urange;
      hit = false;
    }
    const double a = laser.z() + scan.beamAngle(i);
    const Eigen::Vector2d end = from + r * Eigen::Vector2d(std::cos(a), std::sin(a));
    lo = lo.cwiseMin(end);
    hi = hi.cwiseMax(end);
    beams.emplace_back(end, hit);
  }
  map.growToInclude(lo - Eigen::Vector2d::Constant(1.0), hi + Eigen::Vector2d::Constant(1.0));
  for (const auto& b : beams) map.registerBeam(from, b.first, b.second);
}

}  // namespace core
}  // namespace mbot
