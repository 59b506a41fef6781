// Bresenham's line algorithm over grid cells (J. E. Bresenham, "Algorithm for computer control of a
// digital plotter", IBM Systems Journal 4(1), 1965): the 8-connected cells a straight segment
// crosses, with integer arithmetic only. Used for ray tracing in occupancy grids and costmaps.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
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

/// Calls visit(Cell) for every cell the straight segment from (x0, y0) to (x1, y1) passes through,
/// in cell units (world minus origin, over the resolution), in order from the first; where it runs
/// exactly through a cell corner, both cells beside the corner too (a supercover: J. Amanatides and
/// A. Woo, "A fast voxel traversal algorithm for ray tracing", Eurographics 1987). Bresenham's walk
/// between the end cells steps diagonally past a cell that the segment crosses near its corner, so
/// a footprint outline checked with it can reach 2 cm into a wall corner; this one cannot. Stops
/// early and returns false when visit does.
template <typename Visitor>
bool walkSegment(double x0, double y0, double x1, double y1, Visitor&& visit) {
  Cell c{static_cast<int>(std::floor(x0)), static_cast<int>(std::floor(y0))};
  const Cell end{static_cast<int>(std::floor(x1)), static_cast<int>(std::floor(y1))};
  const double dx = x1 - x0, dy = y1 - y0;
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // The segment parameter t (0..1) at which it crosses the next vertical / horizontal cell border,
  // and the increment of t from one border to the next.
  const double tdx = dx != 0.0 ? std::abs(1.0 / dx) : kInf, tdy = dy != 0.0 ? std::abs(1.0 / dy) : kInf;
  double tx = dx > 0.0 ? (c.x + 1 - x0) * tdx : dx < 0.0 ? (x0 - c.x) * tdx : kInf;
  double ty = dy > 0.0 ? (c.y + 1 - y0) * tdy : dy < 0.0 ? (y0 - c.y) * tdy : kInf;
  if (!visit(c)) return false;
  const int steps = std::abs(end.x - c.x) + std::abs(end.y - c.y);
  for (int k = 0; k < steps && !(c == end); ++k) {
    const bool step_x = c.x != end.x && (c.y == end.y || tx <= ty);
    const bool step_y = c.y != end.y && (c.x == end.x || ty <= tx);
    if (step_x && step_y && (!visit(Cell{c.x + sx, c.y}) || !visit(Cell{c.x, c.y + sy}))) return false;
    if (step_x) {
      c.x += sx;
      tx += tdx;
    }
    if (step_y) {
      c.y += sy;
      ty += tdy;
    }
    if (!visit(c)) return false;
  }
  return true;
}

/// The cells of the line from `from` to `to`, both included, in order.
std::vector<Cell> bresenhamLine(Cell from, Cell to);

}  // namespace core
}  // namespace mbot
