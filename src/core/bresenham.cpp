#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {

std::vector<Cell> bresenhamLine(Cell from, Cell to) {
  std::vector<Cell> cells;
  cells.reserve(std::max(std::abs(to.x - from.x), std::abs(to.y - from.y)) + 1);
  walkLine(from, to, [&cells](Cell c) {
    cells.push_back(c);
    return true;
  });
  return cells;
}

}  // namespace core
}  // namespace mbot
