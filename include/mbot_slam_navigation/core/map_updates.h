// A published occupancy map sent as what changed (map_msgs/OccupancyGridUpdate windows, as
// costmap_2d sends costmap_updates), for subscribers on other hosts: the map grown to whole
// blocks, so that its size changes seldom, and the windows over the cells that changed.
#pragma once

#include <cstdint>
#include <vector>

#include "mbot_slam_navigation/core/slam_grid.h"

namespace mbot {
namespace core {

/// A window of a grid [cells]: column x, row y (rows from the lowest y), width x height.
struct GridWindow {
  int x = 0, y = 0, width = 0, height = 0;
};

/// `image` grown with unknown cells (-1) to whole blocks of `block_cells` x `block_cells`, aligned
/// on the cells of its frame (cell (0, 0) has its corner at the frame's origin), so that its size
/// and origin change only when what it holds crosses a block's edge; and, with `cover` (a window
/// in the frame's cells, e.g. the map last sent), grown to cover that too, so that a map whose
/// edge moves back and forth across a block's edge (an optimization moving a wall by a cell) keeps
/// its size. Throws std::invalid_argument for block_cells < 1.
OccupancyImage paddedToBlocks(OccupancyImage image, int block_cells, const GridWindow* cover = nullptr);

/// The window of the frame's cells that `image` covers (its origin on a cell corner of the frame).
GridWindow frameCells(const OccupancyImage& image);

/// Windows covering every cell where `after` differs from `before` (width x height cells each,
/// row-major): the grid is cut into tiles of `tile` x `tile` cells, each shrunk to its changed
/// cells' bounding box, and consecutive changed tiles along a row of tiles share one window where
/// that adds fewer unchanged cells than a message of its own costs (64 bytes). A band of newly seen
/// cells (a robot's laser reach as it drives) is then sent without the unchanged cells around it.
/// Throws std::invalid_argument for sizes that do not match or tile < 1.
std::vector<GridWindow> changedWindows(const std::vector<int8_t>& before, const std::vector<int8_t>& after, int width,
                                       int height, int tile);

}  // namespace core
}  // namespace mbot
