// Ray casting in an occupancy grid: the distance along a ray to the first cell believed occupied.
// Walks cells with Bresenham and returns the exact distance at which the ray enters that cell's
// square, so a grid-based simulated laser or a beam sensor model sees walls where they are.
#pragma once

#include <Eigen/Core>

#include "mbot_slam_navigation/core/occupancy_grid.h"

namespace mbot {
namespace core {

/// Distance [m] from `from` (world, m) along heading `angle_rad` to the first cell whose occupancy
/// probability exceeds `occupied_probability`, or +inf when no such cell lies within `max_range_m`
/// (or the ray leaves the grid first). A start inside an occupied cell returns 0.
double castRay(const OccupancyGrid& grid, const Eigen::Vector2d& from, double angle_rad, double max_range_m,
               double occupied_probability = 0.5);

}  // namespace core
}  // namespace mbot
