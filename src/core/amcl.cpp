#include "mbot_slam_navigation/core/amcl.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "mbot_slam_navigation/core/bresenham.h"
#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

namespace {

constexpr int kOccupiedMin = 65;
constexpr int kFreeMax = 25;
// ROS amcl's kd-tree bin sizes.
constexpr double kBinXY = 0.5;
constexpr double kBinYaw = 10.0 * M_PI / 180.0;
constexpr int kYawBins = 36;

struct BinKey {
  int x, y, a;
  bool operator==(const BinKey& o) const { return x == o.x && y == o.y && a == o.a; }
};
struct BinHash {
  std::size_t operator()(const BinKey& k) const {
    return (static_cast<std::size_t>(static_cast<uint32_t>(k.x)) * 73856093u) ^
           (static_cast<std::size_t>(static_cast<uint32_t>(k.y)) * 19349663u) ^ static_cast<std::size_t>(k.a);
  }
};
BinKey binOf(const Eigen::Vector3d& p) {
  int a = static_cast<int>(std::floor(normalizeAngle(p.z()) / kBinYaw)) % kYawBins;
  if (a < 0) a += kYawBins;  // yaw bins wrap at +-pi (ROS's do not: one cluster may be split in two)
  return {static_cast<int>(std::floor(p.x() / kBinXY)), static_cast<int>(std::floor(p.y() / kBinXY)), a};
}

// The smaller of the angles between a and the forward or backward direction: a robot driving
// backwards turns by pi in atan2 terms, which is no rotation noise source (ROS's trick).
double rotationNoise(double a) { return std::min(std::fabs(normalizeAngle(a)), std::fabs(normalizeAngle(a - M_PI))); }

void requireNonNegative(double v, const char* name) {
  if (!(v >= 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string(name) + " must be >= 0, got " + std::to_string(v));
}

}  // namespace

// ---------------------------------------------------------------------------------------------- map

AmclMap::AmclMap(int width, int height, double resolution, const Eigen::Vector2d& origin,
                 const std::vector<int8_t>& data)
    : width_(width), height_(height), resolution_(resolution), origin_(origin) {
  if (width <= 0 || height <= 0 || data.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("amcl map: " + std::to_string(data.size()) + " values for " + std::to_string(width) +
                                " x " + std::to_string(height) + " cells");
  }
  if (!(resolution > 0.0)) throw std::invalid_argument("amcl map: resolution must be positive");
  state_.resize(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    const int v = data[i];
    state_[i] = v >= kOccupiedMin ? 1 : (v >= 0 && v <= kFreeMax ? -1 : 0);
    if (state_[i] == -1) free_cells_.push_back(static_cast<int>(i));
  }
}

int AmclMap::state(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return 0;
  return state_[static_cast<std::size_t>(y) * width_ + x];
}

const std::vector<float>& AmclMap::occupiedDistance(double max_dist) const {
  if (max_dist == dist_max_) return dist_;
  // distanceTransform measures to the nearest zero pixel: occupied cells are the zeros.
  cv::Mat not_occupied(height_, width_, CV_8UC1);
  for (int y = 0; y < height_; ++y) {
    uint8_t* row = not_occupied.ptr<uint8_t>(y);
    for (int x = 0; x < width_; ++x) row[x] = state_[static_cast<std::size_t>(y) * width_ + x] == 1 ? 0 : 255;
  }
  cv::Mat dist;
  cv::distanceTransform(not_occupied, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  dist_.resize(state_.size());
  const float cap = static_cast<float>(max_dist);
  for (int y = 0; y < height_; ++y) {
    const float* row = dist.ptr<float>(y);
    for (int x = 0; x < width_; ++x) {
      dist_[static_cast<std::size_t>(y) * width_ + x] = std::min(cap, row[x] * static_cast<float>(resolution_));
    }
  }
  dist_max_ = max_dist;
  return dist_;
}

double AmclMap::castRange(double x, double y, double angle, double max_range) const {
  const Cell from{static_cast<int>(std::floor((x - origin_.x()) / resolution_)),
                  static_cast<int>(std::floor((y - origin_.y()) / resolution_))};
  const double ex = x + max_range * std::cos(angle), ey = y + max_range * std::sin(angle);
  const Cell to{static_cast<int>(std::floor((ex - origin_.x()) / resolution_)),
                static_cast<int>(std::floor((ey - origin_.y()) / resolution_))};
  Cell stop = to;
  const bool reached = walkLine(from, to, [&](const Cell& c) {
    if (state(c.x, c.y) > -1) {  // occupied, unknown or off the map: ROS's map_calc_range stops there
      stop = c;
      return false;
    }
    return true;
  });
  if (reached) return max_range;
  const double dx = (stop.x - from.x) * resolution_, dy = (stop.y - from.y) * resolution_;
  return std::min(max_range, std::sqrt(dx * dx + dy * dy));
}

// ---------------------------------------------------------------------------------------- params

void AmclParams::validate() const {
  if (min_particles < 1) throw std::invalid_argument("min_particles must be >= 1, got " + std::to_string(min_particles));
  if (max_particles < min_particles) {
    throw std::invalid_argument("max_particles (" + std::to_string(max_particles) + ") must be >= min_particles (" +
                                std::to_string(min_particles) + ")");
  }
  if (!(kld_err > 0.0 && kld_err < 1.0)) throw std::invalid_argument("kld_err must be in (0, 1), got " + std::to_string(kld_err));
  if (!(kld_z > 0.0)) throw std::invalid_argument("kld_z must be positive, got " + std::to_string(kld_z));
  requireNonNegative(recovery_alpha_slow, "recovery_alpha_slow");
  requireNonNegative(recovery_alpha_fast, "recovery_alpha_fast");
  if (recovery_alpha_slow > 1.0 || recovery_alpha_fast > 1.0) {
    throw std::invalid_argument("recovery_alpha_slow and recovery_alpha_fast must be <= 1");
  }
  requireNonNegative(alpha1, "odom_alpha1");
  requireNonNegative(alpha2, "odom_alpha2");
  requireNonNegative(alpha3, "odom_alpha3");
  requireNonNegative(alpha4, "odom_alpha4");
  requireNonNegative(alpha5, "odom_alpha5");
  if (max_beams < 2) throw std::invalid_argument("laser_max_beams must be >= 2, got " + std::to_string(max_beams));
  requireNonNegative(z_hit, "laser_z_hit");
  requireNonNegative(z_short, "laser_z_short");
  requireNonNegative(z_max, "laser_z_max");
  requireNonNegative(z_rand, "laser_z_rand");
  if (z_hit + z_short + z_max + z_rand <= 0.0) throw std::invalid_argument("laser_z_hit + z_short + z_max + z_rand must be > 0");
  if (!(sigma_hit > 0.0)) throw std::invalid_argument("laser_sigma_hit must be positive, got " + std::to_string(sigma_hit));
  if (!(lambda_short > 0.0)) throw std::invalid_argument("laser_lambda_short must be positive, got " + std::to_string(lambda_short));
  if (!(likelihood_max_dist > 0.0)) {
    throw std::invalid_argument("laser_likelihood_max_dist must be positive, got " + std::to_string(likelihood_max_dist));
  }
}

// ---------------------------------------------------------------------------------------- filter

Amcl::Amcl(const AmclParams& params, unsigned seed) : params_(params), rng_(seed) { params_.validate(); }

void Amcl::setMap(std::shared_ptr<const AmclMap> map) {
  map_ = std::move(map);
  field_map_ = nullptr;
}

void Amcl::initGaussian(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, bool free_only) {
  // Sample through the Cholesky factor, so correlated x-y covariances (rviz never sends them, a
  // saved pose may) are honoured. A non-positive-definite matrix falls back to its diagonal.
  Eigen::Matrix3d l = Eigen::Matrix3d::Zero();
  Eigen::LLT<Eigen::Matrix3d> llt(cov);
  if (llt.info() == Eigen::Success) {
    l = llt.matrixL();
  } else {
    for (int i = 0; i < 3; ++i) l(i, i) = std::sqrt(std::max(0.0, cov(i, i)));
  }
  std::normal_distribution<double> n01(0.0, 1.0);
  particles_.assign(params_.max_particles, AmclParticle{mean, 1.0 / params_.max_particles});
  const bool check = free_only && map_ && !map_->freeCells().empty();
  const double res = map_ ? map_->resolution() : 1.0;
  for (auto& p : particles_) {
    for (int tries = 0; tries < 50; ++tries) {
      const Eigen::Vector3d z(n01(rng_), n01(rng_), n01(rng_));
      p.pose = mean + l * z;
      if (!check) break;
      const int cx = static_cast<int>(std::floor((p.pose.x() - map_->origin().x()) / res));
      const int cy = static_cast<int>(std::floor((p.pose.y() - map_->origin().y()) / res));
      if (map_->state(cx, cy) == -1) break;
    }
    p.pose.z() = normalizeAngle(p.pose.z());
  }
  w_slow_ = w_fast_ = 0.0;
}

Eigen::Vector3d Amcl::randomFreePose() {
  const auto& cells = map_->freeCells();
  std::uniform_int_distribution<std::size_t> pick(0, cells.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int idx = cells[pick(rng_)];
  const double r = map_->resolution();
  return {map_->origin().x() + (idx % map_->width() + unit(rng_)) * r,
          map_->origin().y() + (idx / map_->width() + unit(rng_)) * r, (2.0 * unit(rng_) - 1.0) * M_PI};
}

void Amcl::initUniform() {
  if (!map_ || map_->freeCells().empty()) throw std::logic_error("amcl: global localization needs a map with free cells");
  particles_.resize(params_.max_particles);
  for (auto& p : particles_) p = AmclParticle{randomFreePose(), 1.0 / params_.max_particles};
  w_slow_ = w_fast_ = 0.0;
}

void Amcl::motionUpdate(const Eigen::Vector3d& odom_old, const Eigen::Vector3d& odom_new) {
  const double dx = odom_new.x() - odom_old.x(), dy = odom_new.y() - odom_old.y();
  const double dtheta = normalizeAngle(odom_new.z() - odom_old.z());
  const double trans = std::sqrt(dx * dx + dy * dy);
  std::normal_distribution<double> n01(0.0, 1.0);
  const auto& a = params_;
  if (a.odom_model == OdomModel::kDiff) {
    const double rot1 = trans < 0.01 ? 0.0 : normalizeAngle(std::atan2(dy, dx) - odom_old.z());
    const double rot2 = normalizeAngle(dtheta - rot1);
    const double rot1_noise = rotationNoise(rot1), rot2_noise = rotationNoise(rot2);
    const double sd_rot1 = std::sqrt(a.alpha1 * rot1_noise * rot1_noise + a.alpha2 * trans * trans);
    const double sd_trans =
        std::sqrt(a.alpha3 * trans * trans + a.alpha4 * (rot1_noise * rot1_noise + rot2_noise * rot2_noise));
    const double sd_rot2 = std::sqrt(a.alpha1 * rot2_noise * rot2_noise + a.alpha2 * trans * trans);
    for (auto& p : particles_) {
      const double r1 = normalizeAngle(rot1 - sd_rot1 * n01(rng_));
      const double t = trans - sd_trans * n01(rng_);
      const double r2 = normalizeAngle(rot2 - sd_rot2 * n01(rng_));
      p.pose.x() += t * std::cos(p.pose.z() + r1);
      p.pose.y() += t * std::sin(p.pose.z() + r1);
      p.pose.z() = normalizeAngle(p.pose.z() + r1 + r2);
    }
  } else {
    const double sd_trans = std::sqrt(a.alpha3 * trans * trans + a.alpha1 * dtheta * dtheta);
    const double sd_rot = std::sqrt(a.alpha4 * dtheta * dtheta + a.alpha2 * trans * trans);
    const double sd_strafe = std::sqrt(a.alpha1 * dtheta * dtheta + a.alpha5 * trans * trans);
    const double bearing_odom = trans < 1e-12 ? 0.0 : normalizeAngle(std::atan2(dy, dx) - odom_old.z());
    for (auto& p : particles_) {
      const double bearing = bearing_odom + p.pose.z();
      const double cs = std::cos(bearing), sn = std::sin(bearing);
      const double t = trans + sd_trans * n01(rng_);
      const double r = dtheta + sd_rot * n01(rng_);
      const double s = sd_strafe * n01(rng_);
      p.pose.x() += t * cs + s * sn;
      p.pose.y() += t * sn - s * cs;
      p.pose.z() = normalizeAngle(p.pose.z() + r);
    }
  }
}

int Amcl::sensorUpdate(const LaserScan& scan, const Eigen::Vector3d& laser_pose) {
  if (!map_) throw std::logic_error("amcl: sensorUpdate without a map");
  if (particles_.empty()) throw std::logic_error("amcl: sensorUpdate without particles");
  const double range_max = scan.range_max_m;
  if (!(range_max > 0.0)) throw std::invalid_argument("amcl: scan range_max must be positive");
  const int count = static_cast<int>(scan.ranges_m.size());
  if (count == 0) return 0;
  const int step = std::max(1, (count - 1) / (params_.max_beams - 1));
  const auto& a = params_;

  // Beams in use: ranges below range_min read as range_max (ROS amcl), +inf as range_max.
  struct Beam {
    double range, bearing;
  };
  std::vector<Beam> beams;
  beams.reserve(count / step + 1);
  for (int i = 0; i < count; i += step) {
    double r = scan.ranges_m[i];
    if (std::isnan(r)) continue;
    if (r <= scan.range_min_m) r = range_max;
    if (r > range_max) r = range_max;
    beams.push_back({r, scan.beamAngle(i)});
  }

  if (a.laser_model == LaserModel::kLikelihoodField) {
    // pz^3 per cell for this range_max: pz = z_hit exp(-d^2 / 2 sigma^2) + z_rand / range_max.
    if (field_map_ != map_.get() || field_range_max_ != range_max) {
      const auto& dist = map_->occupiedDistance(a.likelihood_max_dist);
      const double denom = 2.0 * a.sigma_hit * a.sigma_hit, rand = a.z_rand / range_max;
      auto pz3 = [&](double d) {
        const double pz = a.z_hit * std::exp(-d * d / denom) + rand;
        return static_cast<float>(pz * pz * pz);
      };
      field_.resize(dist.size());
      for (std::size_t i = 0; i < dist.size(); ++i) field_[i] = pz3(dist[i]);
      field_outside_ = pz3(a.likelihood_max_dist);
      field_map_ = map_.get();
      field_range_max_ = range_max;
    }
    // Beam end points in the base frame, in cells, once per scan; max readings are skipped (ROS).
    // Structure of arrays and floats: the inner loop is two multiply-adds and one lookup per beam.
    const double inv_res = 1.0 / map_->resolution();
    std::vector<float> ex, ey;
    ex.reserve(beams.size());
    ey.reserve(beams.size());
    const double lc = std::cos(laser_pose.z()), ls = std::sin(laser_pose.z());
    for (const auto& b : beams) {
      if (b.range >= range_max) continue;
      const double bx = b.range * std::cos(b.bearing), by = b.range * std::sin(b.bearing);
      ex.push_back(static_cast<float>((laser_pose.x() + lc * bx - ls * by) * inv_res));
      ey.push_back(static_cast<float>((laser_pose.y() + ls * bx + lc * by) * inv_res));
    }
    const int w = map_->width(), h = map_->height();
    const std::size_t n = ex.size();
    const float* field = field_.data();
    const float outside = field_outside_;
    for (auto& p : particles_) {
      const float c = static_cast<float>(std::cos(p.pose.z())), s = static_cast<float>(std::sin(p.pose.z()));
      const float x0 = static_cast<float>((p.pose.x() - map_->origin().x()) * inv_res);
      const float y0 = static_cast<float>((p.pose.y() - map_->origin().y()) * inv_res);
      double sum = 1.0;
      for (std::size_t i = 0; i < n; ++i) {
        const float fx = x0 + c * ex[i] - s * ey[i];
        const float fy = y0 + s * ex[i] + c * ey[i];
        // floor for negative values too (cells left of or below the map are outside)
        const int cx = static_cast<int>(fx) - (fx < 0.0f);
        const int cy = static_cast<int>(fy) - (fy < 0.0f);
        sum += (static_cast<unsigned>(cx) < static_cast<unsigned>(w) && static_cast<unsigned>(cy) < static_cast<unsigned>(h))
                   ? field[static_cast<std::size_t>(cy) * w + cx]
                   : outside;
      }
      p.weight *= sum;
    }
  } else {
    const double denom = 2.0 * a.sigma_hit * a.sigma_hit;
    for (auto& p : particles_) {
      const Eigen::Vector3d lp = composePose(p.pose, laser_pose);
      double sum = 1.0;
      for (const auto& b : beams) {
        const double expected = map_->castRange(lp.x(), lp.y(), lp.z() + b.bearing, range_max);
        const double z = b.range - expected;
        double pz = a.z_hit * std::exp(-z * z / denom);
        if (z < 0) pz += a.z_short * a.lambda_short * std::exp(-a.lambda_short * b.range);
        if (b.range >= range_max) pz += a.z_max;
        else pz += a.z_rand / range_max;
        sum += pz * pz * pz;
      }
      p.weight *= sum;
    }
  }

  // How well the scan fits at the heaviest particle: the share of returns within kFitTolerance of
  // an occupied cell. The mean weight moves little when the robot is carried to a place that looks
  // alike; this share falls to about a half and is what FitMonitor (nav/localizer.py) watches.
  {
    const AmclParticle* best = &particles_.front();
    for (const auto& p : particles_) {
      if (p.weight > best->weight) best = &p;
    }
    const Eigen::Vector3d lp = composePose(best->pose, laser_pose);
    const auto& dist = map_->occupiedDistance(a.likelihood_max_dist);
    int returns = 0, fitting = 0;
    for (const auto& b : beams) {
      if (b.range >= range_max) continue;
      const double x = lp.x() + b.range * std::cos(lp.z() + b.bearing), y = lp.y() + b.range * std::sin(lp.z() + b.bearing);
      const int cx = static_cast<int>(std::floor((x - map_->origin().x()) / map_->resolution()));
      const int cy = static_cast<int>(std::floor((y - map_->origin().y()) / map_->resolution()));
      ++returns;
      if (cx >= 0 && cy >= 0 && cx < map_->width() && cy < map_->height() &&
          dist[static_cast<std::size_t>(cy) * map_->width() + cx] <= kFitTolerance) {
        ++fitting;
      }
    }
    scan_fit_ = returns > 0 ? static_cast<double>(fitting) / returns : -1.0;
  }

  // Recovery averages track the mean (unnormalized) weight, as ROS's pf_update_sensor.
  double total = 0.0;
  for (const auto& p : particles_) total += p.weight;
  const double w_avg = total / static_cast<double>(particles_.size());
  w_avg_ = w_avg;
  if (w_avg > 0.0 && std::isfinite(w_avg)) {
    w_slow_ = w_slow_ == 0.0 ? w_avg : w_slow_ + a.recovery_alpha_slow * (w_avg - w_slow_);
    w_fast_ = w_fast_ == 0.0 ? w_avg : w_fast_ + a.recovery_alpha_fast * (w_avg - w_fast_);
  }
  normalize();
  return static_cast<int>(beams.size());
}

void Amcl::normalize() {
  double total = 0.0;
  for (const auto& p : particles_) total += p.weight;
  if (!(total > 0.0) || !std::isfinite(total)) {
    for (auto& p : particles_) p.weight = 1.0 / particles_.size();
    return;
  }
  for (auto& p : particles_) p.weight /= total;
}

int Amcl::resampleLimit(int k) const {
  if (k <= 1) return params_.max_particles;
  const double b = 2.0 / (9.0 * (k - 1));
  const double x = 1.0 - b + std::sqrt(b) * params_.kld_z;
  const int n = static_cast<int>(std::ceil((k - 1) / (2.0 * params_.kld_err) * x * x * x));
  return std::clamp(n, params_.min_particles, params_.max_particles);
}

void Amcl::resample() {
  if (particles_.empty()) return;
  normalize();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double w_diff = (params_.recovery_alpha_slow > 0.0 && w_slow_ > 0.0 && map_ && !map_->freeCells().empty())
                            ? std::max(0.0, 1.0 - w_fast_ / w_slow_)
                            : 0.0;

  // Systematic resampling of m particles: one random offset, m evenly spaced pointers into the
  // cumulative weights, one pass over both: O(particles + m).
  auto systematic = [&](int m) {
    std::vector<int> picks(m);
    const double step = 1.0 / m;
    double u = unit(rng_) * step, c = particles_[0].weight;
    std::size_t i = 0;
    for (int j = 0; j < m; ++j, u += step) {
      while (u > c && i + 1 < particles_.size()) c += particles_[++i].weight;
      picks[j] = static_cast<int>(i);
    }
    return picks;
  };

  // How many: KLD-sampling adds particles until their count exceeds the limit for the number of
  // bins they fill. Counted over a systematic sample of max_particles in random order (so any
  // prefix represents the whole distribution), then drawn afresh, systematically, at that size.
  std::vector<int> order = systematic(params_.max_particles);
  std::shuffle(order.begin(), order.end(), rng_);
  std::unordered_map<BinKey, int, BinHash> bins;
  bins.reserve(order.size());
  int n = 0;
  for (int idx : order) {
    ++n;
    bins.emplace(binOf(particles_[idx].pose), 0);
    if (n > resampleLimit(static_cast<int>(bins.size()))) break;
  }
  n = std::max(n, params_.min_particles);

  std::vector<AmclParticle> next;
  next.reserve(n);
  for (int idx : systematic(n)) {
    next.push_back(AmclParticle{w_diff > 0.0 && unit(rng_) < w_diff ? randomFreePose() : particles_[idx].pose, 1.0 / n});
  }
  particles_.swap(next);
  if (w_diff > 0.0) w_slow_ = w_fast_ = 0.0;  // as ROS: start averaging afresh after an injection
}

AmclEstimate Amcl::estimate() const {
  AmclEstimate out;
  if (particles_.empty()) return out;
  // Clusters: connected groups of occupied bins (26-neighbourhood, yaw wrapping).
  std::unordered_map<BinKey, int, BinHash> bin_cluster;
  for (const auto& p : particles_) bin_cluster.emplace(binOf(p.pose), -1);
  int clusters = 0;
  std::vector<BinKey> stack;
  for (auto& kv : bin_cluster) {
    if (kv.second >= 0) continue;
    kv.second = clusters;
    stack.assign(1, kv.first);
    while (!stack.empty()) {
      const BinKey k = stack.back();
      stack.pop_back();
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int da = -1; da <= 1; ++da) {
            const BinKey nb{k.x + dx, k.y + dy, (k.a + da + kYawBins) % kYawBins};
            auto it = bin_cluster.find(nb);
            if (it != bin_cluster.end() && it->second < 0) {
              it->second = clusters;
              stack.push_back(nb);
            }
          }
    }
    ++clusters;
  }
  struct Sum {
    double w = 0, x = 0, y = 0, c = 0, s = 0;
  };
  std::vector<Sum> sums(clusters);
  Sum all;
  for (const auto& p : particles_) {
    Sum& cl = sums[bin_cluster.at(binOf(p.pose))];
    for (Sum* t : {&cl, &all}) {
      t->w += p.weight;
      t->x += p.weight * p.pose.x();
      t->y += p.weight * p.pose.y();
      t->c += p.weight * std::cos(p.pose.z());
      t->s += p.weight * std::sin(p.pose.z());
    }
  }
  const auto best = std::max_element(sums.begin(), sums.end(), [](const Sum& a, const Sum& b) { return a.w < b.w; });
  out.clusters = clusters;
  out.cluster_weight = all.w > 0 ? best->w / all.w : 0.0;
  out.mean = Eigen::Vector3d(best->x / best->w, best->y / best->w, std::atan2(best->s, best->c));
  const double mx = all.x / all.w, my = all.y / all.w;
  for (const auto& p : particles_) {
    const double dx = p.pose.x() - mx, dy = p.pose.y() - my;
    out.covariance(0, 0) += p.weight * dx * dx;
    out.covariance(0, 1) += p.weight * dx * dy;
    out.covariance(1, 1) += p.weight * dy * dy;
  }
  out.covariance.topLeftCorner<2, 2>() /= all.w;
  out.covariance(1, 0) = out.covariance(0, 1);
  const double r = std::sqrt(all.c * all.c + all.s * all.s) / all.w;
  out.covariance(2, 2) = r > 0 ? -2.0 * std::log(std::min(1.0, r)) : 4.0 * M_PI * M_PI;
  return out;
}

}  // namespace core
}  // namespace mbot
