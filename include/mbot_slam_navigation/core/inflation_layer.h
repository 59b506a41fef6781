// costmap_2d's inflation layer: cost falls off with the distance d [m] from the nearest lethal cell:
//   254 at d = 0, 253 while d <= inscribed_radius, then 252 * exp(-cost_scaling_factor *
//   (d - inscribed_radius)) out to inflation_radius, 0 beyond.
// Distances are exact Euclidean distances between cell centres, computed separably and only out to
// the inflation radius: a column pass (the vertical distance to the nearest lethal cell, capped one
// past the radius) then a row pass (the nearest of those over the columns within the radius). A row
// with no lethal cell within the radius is skipped, so the work follows the obstacles (costmap_2d's
// wavefront from its obstacle cells does the same), not the whole grid.
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

/// The lowest cost at which a footprint centred on a cell may touch a lethal cell of `resolution`
/// [m], for a footprint that touches every lethal cell (a square) nearer than `contact_radius` [m]
/// to its centre (contactRadius). Costs follow cell-centre distances, and a lethal cell whose
/// centre is more than inscribed_radius away may still reach into the footprint: the inscribed
/// cost (253) alone lets a planner put the centre where the local planner's footprint check fails.
/// It is the cost at the largest cell-centre distance of a cell that can touch; 253 when that
/// lies beyond inflation_radius (the costs cannot tell it apart) or the footprint is a point.
/// With `clearance` [m], the cost at that distance plus the clearance: below it the footprint
/// keeps at least `clearance` from every obstacle (0 when that lies beyond inflation_radius).
uint8_t contactCost(const InflationParams& params, double resolution, double contact_radius, double clearance = 0.0);

/// A cell window [x0, x1) x [y0, y1) of a costmap (costmap_2d's update bounds, in cells).
struct CellWindow {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  /// The smallest window holding both.
  CellWindow unite(const CellWindow& o) const;
  /// Grown by `cells` on every side, then clipped to a width x height grid.
  CellWindow grown(int cells, int width, int height) const;
};

/// Inflates every lethal cell of `map` in place (cells keep the higher of their cost and the
/// inflated one; unknown cells follow costmap_2d's inflate_unknown rule).
void inflate(Costmap& map, const InflationParams& params);

/// Bounded inflation: `out`'s cells inside `window` become `base`'s (the layers before inflation)
/// raised by the inflation of `base`'s lethal cells, those outside the window included (the window
/// is read with a margin of the radius). Cells outside the window are not touched. `base` and
/// `out` must have the same size. Work is proportional to the window, not the map.
void inflateWindow(const Costmap& base, Costmap& out, const CellWindow& window, const InflationParams& params);

/// Inflation near lethal cells that have boxes (Costmap::box): `out`'s cells inside `window` that
/// are within reach of a contact and near a box take their cost from the clearance of the best of
/// 3 x 3 points in the cell (at thirds of a cell): its distance to the nearest obstacle's outline
/// (a box grown by cell_box::kMargin, or a whole cell), raised by the contact distance's rounding
/// (contactCost's farthest touching centre less `contact_radius`). So a cost below contactCost
/// means the footprint fits somewhere in the cell without touching an obstacle (the laser's
/// precision, not the cell's), and a plan can pass a gap open only within a centimetre or two of
/// its middle wherever the cell centres fall. Also copies `base`'s boxes into `out` over the
/// window. Call after inflateWindow with the same arguments.
void refineNearBoxes(const Costmap& base, Costmap& out, const CellWindow& window, const InflationParams& params,
                     double contact_radius);

}  // namespace core
}  // namespace mbot
