#include "mbot_slam_navigation/core/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {

float probabilityToLogOdds(double p) { return static_cast<float>(std::log(p / (1.0 - p))); }

double logOddsToProbability(float l) { return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(l))); }

LogOddsModel LogOddsModel::fromProbabilities(double p_hit, double p_miss) {
  if (!(p_hit > 0.5 && p_hit < 1.0)) {
    throw std::invalid_argument("LogOddsModel: p_hit must lie in (0.5, 1), got " + std::to_string(p_hit));
  }
  if (!(p_miss > 0.0 && p_miss < 0.5)) {
    throw std::invalid_argument("LogOddsModel: p_miss must lie in (0, 0.5), got " + std::to_string(p_miss));
  }
  LogOddsModel m;
  m.hit = probabilityToLogOdds(p_hit);
  m.miss = probabilityToLogOdds(p_miss);
  return m;
}

OccupancyGrid::OccupancyGrid(int width_cells, int height_cells, double resolution_m,
                             const Eigen::Vector2d& origin_m, const LogOddsModel& model)
    : width_(width_cells), height_(height_cells), resolution_(resolution_m), origin_(origin_m), model_(model) {
  if (width_cells <= 0 || height_cells <= 0) {
    std::ostringstream msg;
    msg << "OccupancyGrid: width and height must be positive, got " << width_cells << " x " << height_cells;
    throw std::invalid_argument(msg.str());
  }
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("OccupancyGrid: resolution must be a positive number of metres, got " +
                                std::to_string(resolution_m));
  }
  if (!origin_m.allFinite()) throw std::invalid_argument("OccupancyGrid: origin must be finite");
  log_odds_.assign(static_cast<std::size_t>(width_) * height_, 0.0f);
  observed_.assign(log_odds_.size(), 0);
}

Cell OccupancyGrid::worldToCell(const Eigen::Vector2d& p) const { return core::worldToCell(origin_, resolution_, p); }

Eigen::Vector2d OccupancyGrid::cellCenter(const Cell& c) const { return core::cellCenter(origin_, resolution_, c); }

void OccupancyGrid::checkContains(const Cell& c) const {
  if (!contains(c)) {
    std::ostringstream msg;
    msg << "OccupancyGrid: cell (" << c.x << ", " << c.y << ") is outside the " << width_ << " x " << height_
        << " grid";
    throw std::out_of_range(msg.str());
  }
}

float OccupancyGrid::logOdds(const Cell& c) const {
  checkContains(c);
  return log_odds_[index(c)];
}

bool OccupancyGrid::observed(const Cell& c) const {
  checkContains(c);
  return observed_[index(c)] != 0;
}

void OccupancyGrid::setLogOdds(const Cell& c, float l) {
  checkContains(c);
  log_odds_[index(c)] = std::clamp(l, model_.min, model_.max);
  observed_[index(c)] = 1;
}

void OccupancyGrid::addLogOdds(const Cell& c, float delta) {
  const std::size_t i = index(c);
  log_odds_[i] = std::clamp(log_odds_[i] + delta, model_.min, model_.max);
  observed_[i] = 1;
}

void OccupancyGrid::integrateBeam(const Eigen::Vector2d& from, const Eigen::Vector2d& to, bool hit) {
  const Cell end = worldToCell(to);
  walkLine(worldToCell(from), end, [&](const Cell& c) {
    if (contains(c)) addLogOdds(c, (c == end && hit) ? model_.hit : model_.miss);
    return true;
  });
}

int OccupancyGrid::integrateScan(const Eigen::Vector3d& sensor_pose, const LaserScan& scan, double usable_range_m) {
  const Eigen::Vector2d from = sensor_pose.head<2>();
  const double clear_range = std::min(usable_range_m, scan.range_max_m);
  int used = 0;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    double length;
    bool hit;
    if (std::isnan(r) || r < scan.range_min_m) {
      continue;  // invalid, or -inf / too close: nothing known along the beam
    } else if (std::isinf(r) || r >= scan.range_max_m) {
      length = clear_range;  // no return: free as far as we trust the sensor
      hit = false;
    } else if (r > usable_range_m) {
      length = usable_range_m;  // a return beyond the trusted range clears only the trusted part
      hit = false;
    } else {
      length = r;
      hit = true;
    }
    const double a = sensor_pose.z() + scan.beamAngle(i);
    integrateBeam(from, from + length * Eigen::Vector2d(std::cos(a), std::sin(a)), hit);
    ++used;
  }
  return used;
}

void OccupancyGrid::growToInclude(const Eigen::Vector2d& p, double margin_m) {
  const int margin = static_cast<int>(std::ceil(margin_m / resolution_));
  const Cell c = worldToCell(p);
  const int add_left = std::max(0, margin - c.x);
  const int add_bottom = std::max(0, margin - c.y);
  const int add_right = std::max(0, c.x + margin + 1 - width_);
  const int add_top = std::max(0, c.y + margin + 1 - height_);
  if (add_left == 0 && add_bottom == 0 && add_right == 0 && add_top == 0) return;

  const int new_width = width_ + add_left + add_right;
  const int new_height = height_ + add_bottom + add_top;
  std::vector<float> log_odds(static_cast<std::size_t>(new_width) * new_height, 0.0f);
  std::vector<uint8_t> observed(log_odds.size(), 0);
  for (int y = 0; y < height_; ++y) {
    const std::size_t src = static_cast<std::size_t>(y) * width_;
    const std::size_t dst = static_cast<std::size_t>(y + add_bottom) * new_width + add_left;
    std::copy_n(log_odds_.begin() + src, width_, log_odds.begin() + dst);
    std::copy_n(observed_.begin() + src, width_, observed.begin() + dst);
  }
  log_odds_ = std::move(log_odds);
  observed_ = std::move(observed);
  origin_ -= Eigen::Vector2d(add_left, add_bottom) * resolution_;
  width_ = new_width;
  height_ = new_height;
}

std::vector<int8_t> OccupancyGrid::toRosData() const {
  std::vector<int8_t> data(log_odds_.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    data[i] = observed_[i] ? static_cast<int8_t>(std::lround(100.0 * logOddsToProbability(log_odds_[i]))) : -1;
  }
  return data;
}

int OccupancyGrid::observedCount() const {
  return static_cast<int>(std::count(observed_.begin(), observed_.end(), uint8_t{1}));
}

}  // namespace core
}  // namespace mbot
