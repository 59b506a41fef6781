// A 2D costmap as costmap_2d defines its values: 0 free, 1..252 inflated (the robot's centre there
// risks a collision, the more the higher), 253 inscribed (the centre there means a collision), 254
// lethal (an obstacle in the cell), 255 no information. ROS-free; layers write into it.
//
// Geometry as OccupancyGrid: `origin` is the world corner [m] of cell (0, 0) in the costmap's
// global frame, rows grow with y.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/cell.h"

namespace mbot {
namespace core {

namespace cost {
constexpr uint8_t kFree = 0;
constexpr uint8_t kInscribed = 253;
constexpr uint8_t kLethal = 254;
constexpr uint8_t kNoInformation = 255;
}  // namespace cost

class Costmap {
 public:
  /// Throws std::invalid_argument for a non-positive size or resolution.
  Costmap(int width, int height, double resolution_m, const Eigen::Vector2d& origin_m, uint8_t fill = cost::kFree);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }
  bool contains(const Cell& c) const { return c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_; }
  // Inline: the local planner converts every footprint corner of every trajectory step.
  Cell worldToCell(const Eigen::Vector2d& p) const { return core::worldToCell(origin_, resolution_, p); }
  Eigen::Vector2d cellCenter(const Cell& c) const { return core::cellCenter(origin_, resolution_, c); }
  std::size_t index(const Cell& c) const { return static_cast<std::size_t>(c.y) * width_ + c.x; }

  uint8_t cost(const Cell& c) const { return costs_[index(c)]; }
  void setCost(const Cell& c, uint8_t v) { costs_[index(c)] = v; }
  const std::vector<uint8_t>& costs() const { return costs_; }
  std::vector<uint8_t>& costs() { return costs_; }
  void fill(uint8_t v);

  /// Moves the window so that its origin is `new_origin` (snapped to whole cells), keeping the
  /// values of cells in both windows and filling the rest with `fill` (rolling windows).
  void moveOrigin(const Eigen::Vector2d& new_origin, uint8_t fill = cost::kNoInformation);

  /// The costmap's values as nav_msgs/OccupancyGrid data, as costmap_2d publishes them: 0 -> 0,
  /// 253 -> 99, 254 -> 100, 255 -> -1, 1..252 scaled to 1..98.
  std::vector<int8_t> toOccupancyData() const;

 private:
  int width_, height_;
  double resolution_;
  Eigen::Vector2d origin_;
  std::vector<uint8_t> costs_;
};

/// costmap_2d's static layer rule for one map value (-1 unknown, 0..100): >= lethal_threshold
/// (100 by default) lethal, -1 no information (or free when !track_unknown), else free.
uint8_t costFromOccupancy(int8_t value, int lethal_threshold = 100, bool track_unknown = true);

}  // namespace core
}  // namespace mbot
