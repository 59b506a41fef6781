#include "mbot_slam_navigation/core/rbpf_slam.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <pthread.h>

#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

MotionModelParams scanOdometryMotion() {
  MotionModelParams m;
  m.srr = 0.01;
  m.srt = 0.02;
  m.str = 0.01;
  m.stt = 0.02;
  return m;
}

void RbpfParams::validate() const {
  if (threads < 1) throw std::invalid_argument("threads must be >= 1, got " + std::to_string(threads));
  if (particles < 1) throw std::invalid_argument("particles must be >= 1, got " + std::to_string(particles));
  if (!(linear_update >= 0.0)) throw std::invalid_argument("linearUpdate must be >= 0");
  if (!(angular_update >= 0.0)) throw std::invalid_argument("angularUpdate must be >= 0");
  if (!(resample_threshold >= 0.0 && resample_threshold <= 1.0)) throw std::invalid_argument("resampleThreshold must lie in [0, 1]");
  if (!(ogain > 0.0)) throw std::invalid_argument("ogain must be positive");
  if (!(delta > 0.0)) throw std::invalid_argument("delta must be positive");
  if (!(xmax > xmin && ymax > ymin)) throw std::invalid_argument("xmax/ymax must exceed xmin/ymin");
  if (!(llsamplerange >= 0.0 && lasamplerange >= 0.0)) throw std::invalid_argument("llsamplerange and lasamplerange must be >= 0");
  if (llsamplerange > 0.0 && !(llsamplestep > 0.0)) throw std::invalid_argument("llsamplestep must be positive");
  if (lasamplerange > 0.0 && !(lasamplestep > 0.0)) throw std::invalid_argument("lasamplestep must be positive");
  motion.validate();
  matcher.validate();
  if (!(best_switch_margin >= 0.0)) throw std::invalid_argument("best_switch_margin must be >= 0");
  if (scan_odometry) tracking.validate();
}

void RbpfParams::shareWith(GraphSlamParams& g) const {
  g.matcher = matcher;
  g.angular_update = angular_update;
  g.temporal_update = temporal_update;
  g.delta = delta;
  g.xmin = xmin;
  g.ymin = ymin;
  g.xmax = xmax;
  g.ymax = ymax;
}

namespace {

// The track's parameters: the user's local SLAM values, the filter's map, no closures.
GraphSlamParams trackingParams(const RbpfParams& p) {
  GraphSlamParams g = p.tracking;
  p.shareWith(g);
  g.closures = false;
  g.background = false;
  g.keep_scan_poses = false;
  return g;
}

}  // namespace

RbpfSlam::RbpfSlam(const RbpfParams& params)
    : params_(params), motion_((params.validate(), params.motion)), matcher_(params.matcher, params.delta), rng_(params.seed) {
  const SlamGrid empty({params_.xmin, params_.ymin}, {params_.xmax, params_.ymax}, params_.delta);
  particles_.assign(params_.particles, Particle{Eigen::Vector3d::Zero(), 0.0, 0.0, empty, nullptr});
  if (params_.scan_odometry) tracker_ = std::make_unique<GraphSlam>(trackingParams(params_));
}

bool RbpfSlam::processScan(const Eigen::Vector3d& wheel_odom, const LaserScan& scan, double time_s) {
  Eigen::Vector3d odom = wheel_odom;
  if (tracker_) {
    // The track starts where odometry is at the first scan, as the map frame does.
    tracker_->processScan(wheel_odom, scan, time_s);
    odom = tracker_->currentPose();
  }
  if (!initialized_) {
    // The map frame starts where odometry is at the first scan, so map and odom coincide there.
    for (Particle& p : particles_) p.pose = odom;
    last_odom_ = odom;
  } else {
    for (Particle& p : particles_) p.pose = motion_.sample(p.pose, odom, last_odom_, rng_);
    const Eigen::Vector3d step = relativePose(last_odom_, odom);
    linear_distance_ += step.head<2>().norm();
    angular_distance_ += std::abs(step.z());
    last_odom_ = odom;
  }
  const bool due = !initialized_ || linear_distance_ > params_.linear_update ||
                   angular_distance_ > params_.angular_update ||
                   (params_.temporal_update >= 0.0 && time_s - last_update_time_ > params_.temporal_update);
  if (!due) return false;

  if (initialized_) {
    const PreparedScan prepared = matcher_.prepare(scan);
    // Particle k is matched by thread k % threads; the calling thread takes share 0. std::async
    // (not a pool that waits spinning) so that an idle filter costs nothing, and a thread's
    // exception reaches the caller through get().
    const int n = std::min<int>(params_.threads, static_cast<int>(particles_.size()));
    auto share = [this, n, &prepared](int k) {
      for (std::size_t i = k; i < particles_.size(); i += n) drawFromProposal(particles_[i], prepared);
    };
    std::vector<std::future<void>> helpers;
    for (int k = 1; k < n; ++k) {
      helpers.push_back(std::async(std::launch::async, [&share, k] {
        pthread_setname_np(pthread_self(), "slam_particles");  // for top -H and /proc
        share(k);
      }));
    }
    share(0);
    for (auto& h : helpers) h.get();
    normalizeAndResample();
  }
  for (Particle& p : particles_) {
    matcher_.registerScan(p.map, p.pose, scan);
    p.node = std::make_shared<const TrajectoryNode>(TrajectoryNode{p.pose, wheel_odom, time_s, p.node});
  }
  choosePublished();
  update_odom_ = odom;
  initialized_ = true;
  linear_distance_ = angular_distance_ = 0.0;
  last_update_time_ = time_s;
  ++updates_;
  return true;
}

void RbpfSlam::drawFromProposal(Particle& p, const PreparedScan& scan) const {
  double score = 0.0;
  const Eigen::Vector3d matched = matcher_.optimize(p.map, p.pose, scan, &score);
  if (score > params_.minimum_score) p.pose = matched;

  // Improved proposal: likelihood on a small grid around the (matched) pose; the gaussian they
  // define is the proposal, their sum (the normalizer) the weight update.
  std::vector<Eigen::Vector3d> offsets;  // from the matched pose; a sample is p.pose moved by one
  std::vector<double> logl;
  const int nl = params_.llsamplerange > 0.0 ? static_cast<int>(std::round(params_.llsamplerange / params_.llsamplestep)) : 0;
  const int na = params_.lasamplerange > 0.0 ? static_cast<int>(std::round(params_.lasamplerange / params_.lasamplestep)) : 0;
  for (int ix = -nl; ix <= nl; ++ix) {
    for (int iy = -nl; iy <= nl; ++iy) {
      for (int ia = -na; ia <= na; ++ia) {
        const Eigen::Vector3d offset(ix * params_.llsamplestep, iy * params_.llsamplestep, ia * params_.lasamplestep);
        const Eigen::Vector3d q(p.pose.x() + offset.x(), p.pose.y() + offset.y(), normalizeAngle(p.pose.z() + offset.z()));
        double s, l;
        matcher_.likelihoodAndScore(p.map, q, scan, &s, &l);
        offsets.push_back(offset);
        logl.push_back(l);
      }
    }
  }
  const double lmax = *std::max_element(logl.begin(), logl.end());
  double sum = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<double> w(logl.size());
  for (std::size_t i = 0; i < logl.size(); ++i) {
    w[i] = std::exp(logl[i] - lmax);
    sum += w[i];
    // The offsets, not the samples less the pose: a heading near +-pi wraps in the samples, and
    // their difference was 2 pi off (a particle turned round at every such update).
    mean += w[i] * offsets[i];
  }
  mean /= sum;
  // The proposal's mean; not a random draw from it: with likelihoods this peaked the gaussian is
  // tiny and drawing from it only adds jitter (it doubled the ACES error in bench/bench_slam.py).
  p.pose = Eigen::Vector3d(p.pose.x() + mean.x(), p.pose.y() + mean.y(), normalizeAngle(p.pose.z() + mean.z()));
  const double log_norm = lmax + std::log(sum / static_cast<double>(logl.size()));
  p.log_weight += log_norm;
  p.weight_sum += log_norm;
}

std::vector<int> lowVarianceResample(const std::vector<double>& weights, double offset) {
  const std::size_t n = weights.size();
  double total = 0.0;
  for (double w : weights) total += w;
  std::vector<int> out;
  out.reserve(n);
  double c = weights.empty() ? 0.0 : weights[0] / total;
  std::size_t i = 0;
  for (std::size_t m = 0; m < n; ++m) {
    const double target = offset + static_cast<double>(m) / static_cast<double>(n);
    while (target > c && i + 1 < n) c += weights[++i] / total;
    out.push_back(static_cast<int>(i));
  }
  return out;
}

void RbpfSlam::normalizeAndResample() {
  // GMapping's normalization: w_i = exp((l_i - l_max) / (ogain * N)) flattens the likelihoods,
  // which are far too peaked for a laser whose beams are not independent.
  const std::size_t n = particles_.size();
  double lmax = -std::numeric_limits<double>::infinity();
  for (const Particle& p : particles_) lmax = std::max(lmax, p.log_weight);
  const double gain = 1.0 / (params_.ogain * static_cast<double>(n));
  std::vector<double> w(n);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += w[i] = std::exp(gain * (particles_[i].log_weight - lmax));
  double sq = 0.0;
  for (double& x : w) {
    x /= sum;
    sq += x * x;
  }
  last_neff_ = 1.0 / sq;
  if (last_neff_ >= params_.resample_threshold * static_cast<double>(n)) return;

  std::uniform_real_distribution<double> u(0.0, 1.0 / static_cast<double>(n));
  std::vector<Particle> next;
  next.reserve(n);
  for (int i : lowVarianceResample(w, u(rng_))) {
    next.push_back(particles_[i]);
    next.back().log_weight = 0.0;
  }
  particles_ = std::move(next);
  ++resamples_;
}

void RbpfSlam::choosePublished() {
  // Each particle's new node has as parent the node its particle had at the last update (a
  // resampled copy: its ancestor's), so the children of the node published then are that
  // lineage's particles.
  int best = 0, lineage = -1;
  for (int i = 0; i < static_cast<int>(particles_.size()); ++i) {
    const Particle& p = particles_[i];
    if (p.weight_sum > particles_[best].weight_sum) best = i;
    if (published_ && p.node->parent == published_ && (lineage < 0 || p.weight_sum > particles_[lineage].weight_sum)) {
      lineage = i;
    }
  }
  const double scale = params_.ogain * static_cast<double>(particles_.size());
  const bool leave = lineage < 0 ||  // the lineage died out at the resampling
                     (particles_[best].weight_sum - particles_[lineage].weight_sum) / scale > params_.best_switch_margin;
  best_ = leave ? best : lineage;
  published_ = particles_[best_].node;
}

Eigen::Vector3d RbpfSlam::currentPose() const {
  const Particle& b = best();
  if (!b.node) return b.pose;
  return composePose(b.node->pose, relativePose(update_odom_, last_odom_));
}

std::vector<TrajectoryNode> RbpfSlam::trajectory() const {
  std::vector<TrajectoryNode> out;
  for (const TrajectoryNode* n = best().node.get(); n; n = n->parent.get()) out.push_back(*n);
  std::reverse(out.begin(), out.end());
  return out;
}

double RbpfSlam::poseEntropy() const {
  const double n = static_cast<double>(particles_.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double sc = 0.0, ss = 0.0;
  for (const Particle& p : particles_) {
    mean.head<2>() += p.pose.head<2>() / n;
    sc += std::cos(p.pose.z());
    ss += std::sin(p.pose.z());
  }
  mean.z() = std::atan2(ss, sc);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Particle& p : particles_) {
    Eigen::Vector3d d = p.pose - mean;
    d.z() = normalizeAngle(d.z());
    cov += d * d.transpose() / n;
  }
  const double det = std::max(cov.determinant(), 1e-300);
  return 0.5 * std::log(std::pow(2.0 * M_PI * M_E, 3) * det);
}

}  // namespace core
}  // namespace mbot
