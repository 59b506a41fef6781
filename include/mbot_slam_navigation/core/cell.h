// Integer cell index of a 2D grid; shared by every grid-shaped type of the core.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace mbot {
namespace core {

/// A cell index: x counts columns (east in the grid's frame), y counts rows (north).
struct Cell {
  int x = 0;
  int y = 0;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
  bool operator!=(const Cell& o) const { return !(*this == o); }
};

/// The cell containing world point p [m] of a grid whose cell (0, 0) has its outer corner at
/// `origin` [m]; may lie outside the grid. Shared by every grid type so the rule exists once.
inline Cell worldToCell(const Eigen::Vector2d& origin, double resolution, const Eigen::Vector2d& p) {
  return Cell{static_cast<int>(std::floor((p.x() - origin.x()) / resolution)),
              static_cast<int>(std::floor((p.y() - origin.y()) / resolution))};
}

/// World position [m] of the centre of cell c.
inline Eigen::Vector2d cellCenter(const Eigen::Vector2d& origin, double resolution, const Cell& c) {
  return origin + Eigen::Vector2d(c.x + 0.5, c.y + 0.5) * resolution;
}

}  // namespace core
}  // namespace mbot
