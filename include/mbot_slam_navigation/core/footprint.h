// Robot footprints as costmap_2d uses them: a polygon in the robot base frame [m] (or a circle of
// robot_radius, as a 16-gon), padded outwards by footprint_padding; its inscribed radius (centre to
// the nearest edge) sets the inflation layer's 253 band, its circumscribed radius (centre to the
// farthest vertex) the planners' worst case.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/costmap.h"

namespace mbot {
namespace core {

using Footprint = std::vector<Eigen::Vector2d>;

/// A circle of `radius_m` as a 16-gon whose edges touch the circle from outside.
Footprint circleFootprint(double radius_m);
/// Each vertex moved `padding_m` away from the centre along its own direction (costmap_2d's rule).
Footprint padFootprint(const Footprint& footprint, double padding_m);
/// Distance [m] from the origin to the nearest edge / farthest vertex.
double inscribedRadius(const Footprint& footprint);
double circumscribedRadius(const Footprint& footprint);
/// [m] A lethal cell nearer than this to the centre is a collision at every heading: the circle's
/// radius for a round footprint (footprintCost checks it as that circle), else the inscribed radius.
double contactRadius(const Footprint& footprint);
/// Throws std::invalid_argument when the polygon has fewer than 3 vertices or does not contain
/// the origin (the robot's centre must lie inside its footprint).
void validateFootprint(const Footprint& footprint);

/// Even-odd test of point `q` against the polygon `corners[0..n)` (any frame, any units).
bool insidePolygon(const Eigen::Vector2d* corners, std::size_t n, const Eigen::Vector2d& q);

/// Whether the footprint at `pose` (x, y, yaw) overlaps the world rectangle `rect` [m] (min x,
/// min y, max x, max y): an edge crosses it, or it lies inside the outline.
bool footprintMeetsRect(const Eigen::Vector3d& pose, const Footprint& footprint, const Eigen::Vector4d& rect);

/// The highest cost under the footprint's outline at `pose` (x, y, yaw; costmap frame) as
/// base_local_planner's CostmapModel checks it: -1 when any outline cell is lethal (254) or
/// outside the map, else the maximum over the outline cells (unknown cells count as 255 only if
/// `unknown_is_obstacle`, else are ignored). The outline's cells are every cell it passes through.
/// A round footprint (robot_radius's 16-gon: at least 8 vertices, all as far from the centre) is
/// checked as the circle through its vertices, so that its cost does not change as it turns.
/// A lethal cell with a box (cell_box) counts only where the outline or the inside meets the box,
/// grown by cell_box::kMargin plus `box_margin` [m]; else it costs 253.
int footprintCost(const Costmap& map, const Eigen::Vector3d& pose, const Footprint& footprint,
                  bool unknown_is_obstacle = false, double box_margin = 0.0);

}  // namespace core
}  // namespace mbot
