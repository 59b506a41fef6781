// costmap_2d's inflation layer: cost falls off with the distance d [m] from the nearest lethal cell:
//   254 at d = 0, 253 while d <= inscribed_radius, then 252 * exp(-cost_scaling_factor *
//   (d - inscribed_radius)) out to inflation_radius, 0 beyond.
// Distances come from OpenCV's exact Euclidean distance transform over the whole window (one pass,
// linear in the cells), not a per-obstacle wavefront.
#pragma once

#include <cstdint>

#include "mbot_slam_navigation/core/costmap.h"

namespace mbot {
namespace core {

struct InflationParams {
  double inscribed_radius = 0.2;      ///< [m] the footprint's inscribed radius
  double inflation_radius = 0.55;     ///< [m] (costmap_2d default)
  double cost_scaling_factor = 10.0;  ///< [1/m] (costmap_2d default)
  bool inflate_unknown = false;       ///< unknown cells take any inflated cost (else only >= 253)
  void validate() const;              ///< std::invalid_argument naming the parameter
};

/// The cost at distance d [m] from an obstacle.
uint8_t inflatedCost(double distance_m, const InflationParams& params);

/// Inflates every lethal cell of `map` in place (cells keep the higher of their cost and the
/// inflated one; unknown cells follow costmap_2d's inflate_unknown rule).
void inflate(Costmap& map, const InflationParams& params);

}  // namespace core
}  // namespace mbot
