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

namespace cell_box {
namespace {
int units(double f) { return std::clamp(static_cast<int>(f * kUnits), 0, kUnits - 1); }
}  // namespace

uint32_t ofPoint(double fx, double fy) {
  const int x = units(fx), y = units(fy);
  return pack(x, y, x + 1, y + 1);
}

uint32_t grow(uint32_t box, double fx, double fy) {
  if (box == kNoBox) return box;
  const int x = units(fx), y = units(fy);
  return pack(std::min(x0(box), x), std::min(y0(box), y), std::max(x1(box), x + 1), std::max(y1(box), y + 1));
}
}  // namespace cell_box

void Costmap::fill(uint8_t v) {
  std::fill(costs_.begin(), costs_.end(), v);
  std::fill(boxes_.begin(), boxes_.end(), cell_box::kNoBox);
}

Eigen::Vector4d Costmap::obstacleBounds(const Cell& c, double margin) const {
  const double x = origin_.x() + c.x * resolution_, y = origin_.y() + c.y * resolution_;
  const uint32_t b = box(index(c));
  if (b == cell_box::kNoBox) return {x, y, x + resolution_, y + resolution_};
  const double u = resolution_ / cell_box::kUnits;
  return {x + cell_box::x0(b) * u - margin, y + cell_box::y0(b) * u - margin, x + cell_box::x1(b) * u + margin,
          y + cell_box::y1(b) * u + margin};
}

void Costmap::moveOrigin(const Eigen::Vector2d& new_origin, uint8_t fill) {
  // Whole cells, rounded: 0.3 m / 0.1 m must be 3 cells, not the 2 that truncating 2.9999 gives.
  const int dx = static_cast<int>(std::lround((new_origin.x() - origin_.x()) / resolution_));
  const int dy = static_cast<int>(std::lround((new_origin.y() - origin_.y()) / resolution_));
  if (dx == 0 && dy == 0) return;
  std::vector<uint8_t> moved(costs_.size(), fill);
  std::vector<uint32_t> moved_boxes(boxes_.size(), cell_box::kNoBox);
  for (int y = 0; y < height_; ++y) {
    const int sy = y + dy;
    if (sy < 0 || sy >= height_) continue;
    for (int x = 0; x < width_; ++x) {
      const int sx = x + dx;
      if (sx < 0 || sx >= width_) continue;
      const std::size_t to = static_cast<std::size_t>(y) * width_ + x, from = static_cast<std::size_t>(sy) * width_ + sx;
      moved[to] = costs_[from];
      if (!boxes_.empty()) moved_boxes[to] = boxes_[from];
    }
  }
  costs_ = std::move(moved);
  boxes_ = std::move(moved_boxes);
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
