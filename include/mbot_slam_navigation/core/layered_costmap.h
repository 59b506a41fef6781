// costmap_2d's layered costmap, ROS-free: its configuration (read from a costmap namespace, both
// styles) and the master grid composed from a static, an obstacle and an inflation layer, and
// costmap filters (keep-out and speed zones: core/costmap_filter.h).
//
// Configuration styles, as costmap_2d reads them:
// - pre-Hydro (the tutorials): `static_map`, the obstacle keys (`observation_sources`,
//   `obstacle_range`...) and the inflation keys at the top level of the costmap namespace;
// - `plugins: [{name: ..., type: costmap_2d::StaticLayer}, ...]` with each layer's keys in
//   `<costmap>/<name>/` (falling back to the top level, as ROS copies them there).
// Filters go into either style's costmap as `filters: [{name: ..., type: ...}]` (Nav2's list,
// entries also as a name with `<name>/plugin`), or as layers in `plugins`: types
// nav2_costmap_2d::KeepoutFilter, nav2_costmap_2d::SpeedFilter and
// costmap_prohibition_layer_namespace::CostmapProhibitionLayer. Wherever they are listed, keep-out
// zones are combined before inflation.
//
// Values are costmap_2d's (0 free, 1..252 inflated, 253 inscribed, 254 lethal, 255 unknown); the
// grid's cell (0, 0) has its corner at `origin` [m] in the costmap's global_frame.
//
// Updates are bounded, as costmap_2d's updateBounds / updateCosts: each update recomposes and
// re-inflates only the window that changed (the cells a scan's rays reached, the cells of a map
// that differ from the last one, the footprint's old and new places), grown by the inflation
// radius. A new map of another size, a moved rolling window or a reset redo the whole grid.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/costmap_filter.h"
#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/inflation_layer.h"
#include "mbot_slam_navigation/core/laser_scan.h"
#include "mbot_slam_navigation/core/params.h"

namespace mbot {
namespace core {

struct StaticLayerConfig {
  std::string name = "static_layer";
  std::string map_topic = "map";
  bool first_map_only = false, subscribe_to_updates = false, track_unknown_space = true, use_maximum = false;
  int lethal_cost_threshold = 100, unknown_cost_value = -1;
  bool trinary_costmap = true, enabled = true;
};

/// expected_update_rate [s] of a source that does not set it. costmap_2d's default is 0 (never
/// stale), so a laser that falls silent leaves the robot driving blind; here it stops after this
/// long. An explicit 0 keeps costmap_2d's behaviour.
constexpr double kUnsetExpectedUpdateRate = 2.0;

struct ObservationSourceConfig {
  std::string name, topic, sensor_frame;  ///< sensor_frame empty: each scan's header frame
  double observation_persistence = 0.0, expected_update_rate = 0.0;  ///< [s]
  bool clearing = false, marking = true;
  double max_obstacle_height = 2.0, min_obstacle_height = 0.0;       ///< [m]
  double obstacle_range = 2.5, raytrace_range = 3.0;                 ///< [m]
  double raytrace_end_margin = 0.03;  ///< [m] ours: ObservationSourceParams::raytrace_end_margin
  bool inf_is_valid = true;  ///< ROS's default is false (then +inf clears nothing); see docs/navigation.md
  bool too_close_is_obstacle = true;  ///< ours: -inf marks range_min (costmap_2d ignores it)
};

struct ObstacleLayerConfig {
  std::string name = "obstacle_layer";
  std::vector<ObservationSourceConfig> sources;
  bool track_unknown_space = false, footprint_clearing_enabled = true, enabled = true;
  int combination_method = 1;  ///< 0 overwrite, 1 maximum
};

struct InflationLayerConfig {
  std::string name = "inflation_layer";
  double inflation_radius = 0.55, cost_scaling_factor = 10.0;
  bool inflate_unknown = false, enabled = true;
};

struct CostmapConfig {
  std::string name;
  std::string global_frame = "map", robot_base_frame = "base_link";
  double transform_tolerance = 0.3, update_frequency = 5.0;
  double publish_frequency = 1.0;  ///< ROS's default is 0 (never published); rviz users expect a costmap
  bool rolling_window = false, always_send_full_costmap = false;
  double width = 10.0, height = 10.0, resolution = 0.05, origin_x = 0.0, origin_y = 0.0;  ///< [m]
  double footprint_padding = 0.01;
  Footprint footprint;  ///< padded, robot frame [m]
  double inscribed_radius = 0.0, circumscribed_radius = 0.0;
  std::vector<std::pair<std::string, std::string>> layers;  ///< (name, kind: static, obstacle, inflation, keepout, speed) in order
  std::optional<StaticLayerConfig> static_layer;
  std::optional<ObstacleLayerConfig> obstacle_layer;
  std::optional<InflationLayerConfig> inflation_layer;
  std::vector<FilterConfig> filters;  ///< keep-out and speed filters; one with an error is not used
};

/// Reads the namespace `ns_prefix/name` (its values given), warning about misplaced and misspelt
/// keys. Throws ParamError naming the key for values that cannot be used.
CostmapConfig readCostmapConfig(const std::string& name, const ParamValue& values, const Warn& warn,
                                const std::string& ns_prefix = "");

/// A footprint parameter: a list of [x, y] points, or the same written as a string.
Footprint parseFootprint(const ParamValue& value, const std::string& where);

/// costmap_2d's StaticLayer::interpretValue for one OccupancyGrid value.
uint8_t staticCost(int8_t value, const StaticLayerConfig& params);

class LayeredCostmap {
 public:
  LayeredCostmap(const CostmapConfig& config, Warn warn);
  const CostmapConfig& config() const { return config_; }
  /// False while a static layer waits for its first map.
  bool ready() const { return !config_.static_layer || map_received_; }

  /// A new map for the static layer (OccupancyGrid data, rows = y, origin of cell (0, 0) [m]).
  void setMap(const std::vector<int8_t>& data, int width, int height, const Eigen::Vector2d& origin, double resolution);
  /// A window of the static layer's map replaced (map_msgs/OccupancyGridUpdate: `data` rows of
  /// `width` cells, the window's corner at cell (x, y) of the current map). False, changing
  /// nothing, before the first map or for a window outside it (the caller waits for a whole map).
  bool patchMap(const std::vector<int8_t>& data, int x, int y, int width, int height);
  /// Buffers one scan of source `source` (sensor pose in the global frame, height [m] above it).
  /// False (warning once per source) when the sensor's height is outside the source's
  /// [min_obstacle_height, max_obstacle_height]: costmap_2d drops every point of such a scan.
  bool addScan(std::size_t source, double stamp, const Eigen::Vector3d& sensor_pose, double sensor_height,
               const LaserScan& scan);
  /// Sources whose expected_update_rate is overdue at `now` [s] (costmap_2d's isCurrent is false),
  /// each as "name (topic T): why" for the user's message.
  std::vector<std::string> staleSources(double now) const;
  /// One update cycle at `robot_pose` (global frame); returns the window of cells that changed.
  CellWindow update(const Eigen::Vector3d& robot_pose);
  /// Clears the obstacle layer (clear_costmaps), or only outside a square of side `keep.z()`
  /// centred on (keep.x(), keep.y()) (ClearCostmapRecovery's reset_distance).
  void resetObstacles(const std::optional<Eigen::Vector3d>& keep = std::nullopt);

  const Costmap& master() const { return master_; }
  /// contactCost of this costmap's footprint, inflation and resolution: the lowest cost at which a
  /// centre's footprint may cover a lethal cell (253 without an inflation layer).
  uint8_t contactCost() const;
  /// [m] The clearance a plan keeps where it can (roomyCost).
  static constexpr double kRoomyClearance = 0.02;
  /// The cost below which the footprint keeps kRoomyClearance from every obstacle (contactCost
  /// without an inflation layer): the global planner's first threshold, so that a plan squeezes
  /// through a gap with a centimetre to spare only where no roomier way is known.
  uint8_t roomyCost() const;

  /// A mask for filter `index` of config().filters (OccupancyGrid data, as setMap). Throws
  /// std::invalid_argument saying why when it cannot be used (its size, or a resolution other
  /// than the costmap's); the filter then keeps its last good mask.
  void setFilterMask(std::size_t index, const std::vector<int8_t>& data, int width, int height,
                     const Eigen::Vector2d& origin, double resolution);
  /// Problems found since the last call (a filter dropped because a new map has another
  /// resolution than its mask), each naming the filter; for the user's error messages.
  std::vector<std::string> takeFilterErrors();
  /// The keep-out zone at world point `p` [m]: "ZONE (filter NAME)", or "" when none.
  std::string keepoutZoneAt(const Eigen::Vector2d& p) const;
  struct SpeedLimit {
    bool limited = false;
    double value = 0.0;    ///< percent of max_vel_x, or [m/s] when !percent
    bool percent = true;
    std::string zone;      ///< "ZONE (filter NAME)"
  };
  /// The lowest speed limit under the footprint at `pose` (global frame).
  SpeedLimit speedLimitAt(const Eigen::Vector3d& pose) const;
  /// The mask filter `index` uses (not valid before one arrived).
  const FilterMask& filterMask(std::size_t index) const { return masks_.at(index); }

  /// Index of the observation source named `name`, or -1.
  int sourceIndex(const std::string& name) const;

 private:
  struct Observation {
    double stamp;
    Eigen::Vector3d pose;
    LaserScan scan;
  };
  void resize(int width, int height, const Eigen::Vector2d& origin, double resolution);
  void enableBoxes();
  void compose(const CellWindow& window);
  void applyKeepout(const CellWindow& window);
  bool filterUsable(std::size_t index) const;
  CellWindow cellsAround(const Eigen::Vector2d& centre, double radius_m) const;

  CostmapConfig config_;
  Warn warn_;
  InflationParams inflation_;
  uint8_t obstacle_default_, default_value_;
  Costmap static_, obstacle_, base_, master_;  // base_: the layers composed, before inflation
  bool static_valid_ = false, map_received_ = false;
  std::vector<std::vector<Observation>> observations_;  // not applied yet, or kept by observation_persistence
  std::vector<double> last_stamp_;                       // [s] per source, the newest scan's; NaN before any
  std::vector<bool> height_warned_;
  std::vector<FilterMask> masks_;            // per config_.filters
  std::vector<std::string> filter_errors_;  // not yet taken
  CellWindow dirty_;        // cells whose layers changed since the last update
  bool full_ = true;        // the whole grid must be recomposed
};

}  // namespace core
}  // namespace mbot
