// Bresenham's line algorithm over grid cells (J. E. Bresenham, "Algorithm for computer control of a
// digital plotter", IBM Systems Journal 4(1), 1965): the 8-connected cells a straight segment
// crosses, with integer arithmetic only. Used for ray tracing in occupancy grids and costmaps.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "mbot_slam_navigation/core/cell.h"

namespace mbot {
namespace core {

/// Calls visit(Cell) for every cell of the line from `from` to `to`, both ends included, in order
/// from `from`. If visit returns false the walk stops early (a ray that hit something). Returns
/// true when the walk reached `to`. Header-only because it sits in every ray-tracing hot loop.
template <typename Visitor>
bool walkLine(Cell from, Cell to, Visitor&& visit) {
  const int dx = std::abs(to.x - from.x);
  const int dy = -std::abs(to.y - from.y);
  const int sx = from.x < to.x ? 1 : -1;
  const int sy = from.y < to.y ? 1 : -1;
  int err = dx + dy;
  Cell c = from;
  while (true) {
    if (!visit(c)) return false;
    if (c == to) return true;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      c.x += sx;
    }
    if (e2 <= dx) {
      err += dx;
      c.y += sy;
    }
  }
}

/// The cells of the line from `from` to `to`, both included, in order.
std::vector<Cell> bresenhamLine(Cell from, Cell to);

}  // namespace core
}  // namespace mbot
