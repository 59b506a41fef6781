// costmap_2d's obstacle layer for laser scans, on one Costmap the layer owns: each scan first
// clears (ray traces to free) the cells between the sensor and each beam's end, then marks the end
// points as lethal. Ranges follow REP 117.
//   - marking: a return closer than obstacle_range marks its end cell lethal;
//   - clearing: every beam clears up to its end (exclusive) or raytrace_range, whichever is nearer;
//     a return's beam stops raytrace_end_margin short of the return (the laser's noise);
//     +inf (no return within range_max) clears to min(raytrace_range, range_max) when
//     inf_is_valid, as costmap_2d does for `inf_is_valid: true`;
//   - -inf (REP 117: an object nearer than range_min) marks the cell at range_min along its beam
//     when too_close_is_obstacle (ours; costmap_2d drops it): a person who walks into the robot
//     and covers its laser is then in the costmap, where the robot is, and it does not drive on
//     into them on the strength of marks from before;
//   - NaN, finite returns below range_min (drivers' error codes) and -inf otherwise do nothing;
//   - a layer with boxes (Costmap::enableBoxes) keeps in each marked cell the box of the latest
//     scan's returns in it (cell_box); -inf marks are whole cells.
// Frames: `sensor_pose` is the laser in the costmap's global frame (x [m], y [m], yaw [rad]).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/laser_scan.h"

namespace mbot {
namespace core {

struct ObservationSourceParams {
  double obstacle_range = 2.5;   ///< [m] `obstacle_range` (costmap_2d default 2.5)
  double raytrace_range = 3.0;   ///< [m] `raytrace_range` (default 3.0)
  /// [m] A return clears only the cells its beam leaves more than this short of its end (ours;
  /// 0: costmap_2d's rule, every cell but the end's).
  double raytrace_end_margin = 0.03;
  bool marking = true;
  bool clearing = true;
  bool inf_is_valid = true;      ///< +inf clears (a simulated or real laser that reports "nothing")
  bool too_close_is_obstacle = true;  ///< -inf marks range_min (costmap_2d: ignored)
  void validate() const;         ///< std::invalid_argument naming the parameter
};

/// Applies one scan to `layer`; returns the number of cells marked. `too_close`, when given,
/// also receives the cells marked for -inf readings, so that a caller whose footprint clearing
/// would wipe them (they lie inside the footprint when the laser does) can mark them again after it.
int updateWithScan(Costmap& layer, const Eigen::Vector3d& sensor_pose, const LaserScan& scan,
                   const ObservationSourceParams& params, std::vector<Cell>* too_close = nullptr);

}  // namespace core
}  // namespace mbot
