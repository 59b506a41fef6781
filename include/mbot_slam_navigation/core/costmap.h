// A 2D costmap as costmap_2d defines its values: 0 free, 1..252 inflated (the robot's centre there
// risks a collision, the more the higher), 253 inscribed (the centre there means a collision), 254
// lethal (an obstacle in the cell), 255 no information. ROS-free; layers write into it.
//
// Geometry as OccupancyGrid: `origin` is the world corner [m] of cell (0, 0) in the costmap's
// global frame, rows grow with y.
#pragma once

#include <algorithm>
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

/// Where in a lethal cell its obstacle was seen: the box of the laser returns that fell in it, in
/// 1/254ths of the cell from its corner (x0, y0, x1, y1, each 0..254), packed in 32 bits. kNoBox:
/// the whole cell is the obstacle (a map's cell, a keep-out zone, a mark at range_min). At 0.05 m
/// cells the whole cell rounds a 0.46 m gap for a 0.42 m footprint to anything from 0.36 to 0.46 m;
/// the box keeps where the surface is to the laser's precision.
namespace cell_box {
constexpr uint32_t kNoBox = 0xFFFFFFFFu;
constexpr int kUnits = 254;        ///< box units per cell
/// [m] Every box is grown by this before a footprint is checked against it or a distance taken
/// to it: the parts of a surface between two returns, and a face seen at a grazing angle.
constexpr double kMargin = 0.01;
inline uint32_t pack(int x0, int y0, int x1, int y1) {
  return static_cast<uint32_t>(x0) | static_cast<uint32_t>(y0) << 8 | static_cast<uint32_t>(x1) << 16 |
         static_cast<uint32_t>(y1) << 24;
}
inline int x0(uint32_t b) { return b & 0xFF; }
inline int y0(uint32_t b) { return (b >> 8) & 0xFF; }
inline int x1(uint32_t b) { return (b >> 16) & 0xFF; }
inline int y1(uint32_t b) { return (b >> 24) & 0xFF; }
/// The box of one point at fraction (fx, fy) in [0, 1) of its cell.
uint32_t ofPoint(double fx, double fy);
/// `box` grown to hold the point at fraction (fx, fy); kNoBox stays kNoBox.
uint32_t grow(uint32_t box, double fx, double fy);
/// Squared distance from point (x, y) to the rectangle `rect` (min x, min y, max x, max y), in
/// the units of both; 0 inside.
inline double squaredDistance(const Eigen::Vector4d& rect, double x, double y) {
  const double dx = std::max(std::max(rect[0] - x, x - rect[2]), 0.0), dy = std::max(std::max(rect[1] - y, y - rect[3]), 0.0);
  return dx * dx + dy * dy;
}
}  // namespace cell_box

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

  /// Boxes (cell_box) for lethal cells: off until enabled, then one per cell, kNoBox where none.
  /// setCost leaves a cell's box alone; writers of lethal cells set or clear it.
  void enableBoxes() { if (boxes_.empty()) boxes_.assign(costs_.size(), cell_box::kNoBox); }
  bool hasBoxes() const { return !boxes_.empty(); }
  uint32_t box(std::size_t index) const { return boxes_.empty() ? cell_box::kNoBox : boxes_[index]; }
  void setBox(std::size_t index, uint32_t b) { if (!boxes_.empty()) boxes_[index] = b; }
  /// The lethal cell `c`'s obstacle as a world rectangle [m] (min x, min y, max x, max y), its box
  /// grown by `margin` [m], or the whole cell when it has none.
  Eigen::Vector4d obstacleBounds(const Cell& c, double margin) const;

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
  std::vector<uint32_t> boxes_;  // empty: no boxes
};

/// costmap_2d's static layer rule for one map value (-1 unknown, 0..100): >= lethal_threshold
/// (100 by default) lethal, -1 no information (or free when !track_unknown), else free.
uint8_t costFromOccupancy(int8_t value, int lethal_threshold = 100, bool track_unknown = true);

}  // namespace core
}  // namespace mbot
