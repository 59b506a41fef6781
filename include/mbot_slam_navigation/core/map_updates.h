// A published occupancy map sent as what changed (map_msgs/OccupancyGridUpdate windows, as
// costmap_2d sends costmap_updates), for subscribers on other hosts: the map grown to whole
// blocks, so that its size changes seldom, and the windows over the cells that changed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
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

/// A window of a map and its new cells (row-major), stamped with the time of the map it belongs
/// to [ns]: a map_msgs/OccupancyGridUpdate.
struct MapUpdate {
  int64_t stamp_ns = 0;
  GridWindow window;
  std::vector<int8_t> data;
};

/// The subscriber's side of a map received whole and as updates on two topics, as slam_gmapping
/// and map_merge send it with publish_updates (and costmap_2d its costmap and costmap_updates).
/// Two topics are two connections: an update can arrive before the whole map that was sent before
/// it, and be lost under it, or not fit the map held because that whole map changed the size.
/// The log keeps every update newer than the whole map held, so that each whole map that arrives
/// gets the updates newer than it applied again, and updates that came first are not lost. An
/// update is newer than a whole map when its stamp is later: a publisher stamps each map (whole, or
/// its updates) with the time it was made, and a whole map holds every change made up to its stamp.
class MapUpdateLog {
 public:
  /// At most `max_held` updates and `max_bytes` of their cells are kept (the oldest are dropped
  /// first): our publishers send a whole map every minute or so, which empties the log, but one
  /// that never does (costmap_2d sends its costmap whole only to new subscribers) must not fill
  /// the memory.
  explicit MapUpdateLog(std::size_t max_held = 20000, std::size_t max_bytes = 32u << 20)
      : max_held_(max_held), max_bytes_(max_bytes) {}

  /// An update arrived. Returns whether to apply it to the map held now: false before the first
  /// whole map and for an update not newer than the whole map held (that map has it already).
  /// Every update newer than the whole map held is kept for the next whole map. An update without
  /// a stamp (0) cannot be ordered: it is applied to the map held and not kept.
  bool update(MapUpdate u);

  /// A whole map stamped `stamp_ns` arrived at `now_ns`: returns the updates to apply to it, in the
  /// order they came (those newer than it), and forgets the older ones. A whole map older than the
  /// one held is either stale (a latched map that a publisher sent a new subscriber after a newer
  /// one, as rospy and, by a narrow race, roscpp can): nullopt, not to be taken; or, when the clock
  /// is now behind the map held (a simulation reset), the start of a new log. A whole map without a
  /// stamp (0) is always taken, and starts a new log.
  std::optional<std::vector<MapUpdate>> whole(int64_t stamp_ns, int64_t now_ns);

  /// The updates kept.
  std::size_t held() const { return held_.size(); }

 private:
  std::size_t max_held_, max_bytes_, held_bytes_ = 0;
  bool has_whole_ = false;
  int64_t whole_stamp_ns_ = 0;
  std::deque<MapUpdate> held_;
};

}  // namespace core
}  // namespace mbot
