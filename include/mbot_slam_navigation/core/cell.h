// Integer cell index of a 2D grid; shared by every grid-shaped type of the core.
#pragma once

namespace mbot {
namespace core {

/// A cell index: x counts columns (east in the grid's frame), y counts rows (north).
struct Cell {
  int x = 0;
  int y = 0;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
  bool operator!=(const Cell& o) const { return !(*this == o); }
};

}  // namespace core
}  // namespace mbot
