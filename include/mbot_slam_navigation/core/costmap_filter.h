// Costmap filters, ROS-free: Nav2's KeepoutFilter and SpeedFilter and ROS 1's
// costmap_prohibition_layer. A filter is a mask over the floor, given as nav_msgs/OccupancyGrid
// values (a mask image served by map_server: the darker a pixel, the higher its value) or as
// polygons [m] in the costmap's global_frame, and a meaning for its values:
//
// - keepout: a cell's value v raises the cost there: 100 lethal, 1..99 scaled to 1..252 (the
//   planners avoid it the more, the higher), 0 and -1 leave the cost alone. Keep-out cells are
//   combined into the costmap before inflation, so a zone is inflated as a wall is and the robot's
//   footprint, not only its centre, stays out of it (Nav2 applies its filters after inflation).
// - speed: a cell's value v limits the speed to base + multiplier * v: a percentage of the local
//   planner's max_vel_x (speed_limit_in_percent, the default) or [m/s]; 0 and -1 do not limit.
//
// A zone is a connected region (8-connected) of the mask's non-zero cells. It is named by its
// polygon's name, or "#K at (x, y)" with the centre of its cells [m] for a mask.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace mbot {
namespace core {

struct ZonePolygon {
  std::string name;
  std::vector<Eigen::Vector2d> points;  ///< [m], global_frame
};

struct FilterConfig {
  enum class Kind { kKeepout, kSpeed };
  std::string name, type;  ///< the layer's name and type as given
  Kind kind = Kind::kKeepout;
  std::string mask_topic;  ///< nav_msgs/OccupancyGrid mask ("": polygons only)
  std::vector<ZonePolygon> zones;
  double base = 0.0, multiplier = 1.0;  ///< speed: limit = base + multiplier * value
  bool percent = true;                  ///< speed: the limit is a percentage of max_vel_x (else [m/s])
  bool enabled = true;
  std::string error;  ///< why the filter cannot be used; empty when it can
};

/// The cost a keep-out mask value puts on a cell (0: none).
uint8_t keepoutCost(int8_t value);

/// One filter's mask: values, zones, and look-ups in world coordinates.
class FilterMask {
 public:
  /// OccupancyGrid data (rows = y, cell (0, 0)'s corner at `origin` [m]). Throws
  /// std::invalid_argument saying why for a size that does not match the data.
  void set(const std::vector<int8_t>& data, int width, int height, const Eigen::Vector2d& origin, double resolution);
  /// The polygons drawn at `resolution` [m/cell] into a grid covering them (value 100 inside).
  /// Throws std::invalid_argument for a polygon of fewer than 3 points.
  void setPolygons(const std::vector<ZonePolygon>& zones, double resolution);
  bool valid() const { return width_ > 0; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<int8_t>& data() const { return data_; }

  /// The column / row of the mask holding world x / y [m] (may lie outside the mask).
  int column(double x) const;
  int row(double y) const;
  /// The value at world point `p` [m]; -1 outside the mask.
  int8_t valueAt(const Eigen::Vector2d& p) const;
  /// The zone at `p` (index into zoneNames()), or -1.
  int zoneAt(const Eigen::Vector2d& p) const;
  const std::vector<std::string>& zoneNames() const { return zone_names_; }
  /// The runs [begin, end) of non-zero cells of row `r`, left to right (a mask is mostly empty:
  /// combining it into a costmap visits its zones' cells only).
  const std::vector<std::pair<int, int>>& runs(int r) const { return runs_[r]; }

 private:
  void labelZones(const std::vector<std::string>& names);
  void findRuns();

  int width_ = 0, height_ = 0;
  double resolution_ = 0.0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  std::vector<int8_t> data_;
  std::vector<int> labels_;  ///< per cell: zone index, -1 outside every zone
  std::vector<std::string> zone_names_;
  std::vector<std::vector<std::pair<int, int>>> runs_;  ///< per row
};

}  // namespace core
}  // namespace mbot
