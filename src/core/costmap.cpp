#include "mbot_slam_navigation/core/costmap.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mbot {
namespace core {

Costmap::Costmap(int width, int height, double resolution_m, const Eigen::Vector2d& origin_m, uint8_t fill)
    : width_(width), height_(height), resolution_(resolution_m), origin_(origin_m) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("Costmap: size must be positive, got " + std::to_string(width) + " x " + std::to_string(height));
  }
  if (!(resolution_m > 0.0)) throw std::invalid_argument("Costmap: resolution must be positive");
  costs_.assign(static_cast<std::size_t>(width) * height, fill);
}

void Costmap::fill(uint8_t v) { std::fill(costs_.begin(), costs_.end(), v); }

void Costmap::moveOrigin(const Eigen::Vector2d& new_origin, uint8_t fill) {
  // Whole cells, rounded: 0.3 m / 0.1 m must be 3 cells, not the 2 that truncating 2.9999 gives.
  const int dx = static_cast<int>(std::lround((new_origin.x() - origin_.x()) / resolution_));
  const int dy = static_cast<int>(std::lround((new_origin.y() - origin_.y()) / resolution_));
  if (dx == 0 && dy == 0) return;
  std::vector<uint8_t> moved(costs_.size(), fill);
  for (int y = 0; y < height_; ++y) {
    const int sy = y + dy;
    if (sy < 0 || sy >= height_) continue;
    for (int x = 0; x < width_; ++x) {
      const int sx = x + dx;
      if (sx >= 0 && sx < width_) moved[static_cast<std::size_t>(y) * width_ + x] = costs_[static_cast<std::size_t>(sy) * width_ + sx];
    }
  }
  costs_ = std::move(moved);
  origin_ += Eigen::Vector2d(dx, dy) * resolution_;
}

std::vector<int8_t> Costmap::toOccupancyData() const {
  std::vector<int8_t> out(costs_.size());
  for (std::size_t i = 0; i < costs_.size(); ++i) {
    const uint8_t c = costs_[i];
    if (c == cost::kFree) out[i] = 0;
    else if (c == cost::kInscribed) out[i] = 99;
    else if (c == cost::kLethal) out[i] = 100;
    else if (c == cost::kNoInformation) out[i] = -1;
    else out[i] = static_cast<int8_t>(1 + (97 * (c - 1)) / 251);  // 1..252 -> 1..98
  }
  return out;
}

uint8_t costFromOccupancy(int8_t value, int lethal_threshold, bool track_unknown) {
  if (value < 0) return track_unknown ? cost::kNoInformation : cost::kFree;
  if (value >= lethal_threshold) return cost::kLethal;
  return cost::kFree;
}

}  // namespace core
}  // namespace mbot
