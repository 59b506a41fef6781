// Shortest path lengths over a grid from one cell: the exploration's measure of how far each
// frontier cell is for the robot (Dijkstra, 8-connected, diagonal steps sqrt(2), never cutting
// the corner of a blocked cell).
#pragma once

#include <cstdint>
#include <vector>

#include "mbot_slam_navigation/core/cell.h"

namespace mbot {
namespace core {

/// Path lengths [cells] from `start` to every cell of a width x height row-major grid, moving only
/// through cells whose `passable` value is non-zero (the start cell counts as passable whatever it
/// holds: a robot may stand inside an inflated zone). Unreachable cells get -1. Throws
/// std::invalid_argument when `passable` has the wrong size or `start` lies outside the grid.
std::vector<float> pathLengths(const std::vector<uint8_t>& passable, int width, int height, const Cell& start);

/// The n x n matrix (row-major, [cells]) of path lengths between `cells` over the same grid, each
/// of them counted passable: symmetric, 0 on the diagonal, -1 between cells not connected. Each
/// search stops when the cells it is for are reached, so cells near each other cost little however
/// large the grid. Throws std::invalid_argument when `passable` has the wrong size or a cell lies
/// outside the grid.
std::vector<double> pathLengthsBetween(const std::vector<uint8_t>& passable, int width, int height,
                                       const std::vector<Cell>& cells);

}  // namespace core
}  // namespace mbot
