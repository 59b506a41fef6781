#include "mbot_slam_navigation/core/map_updates.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mbot {
namespace core {

namespace {
int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

/// What a window costs beyond its cells [bytes]: the message's header (stamp, frame), its window
/// and TCPROS's length.
constexpr long kWindowCost = 64;

/// Changed cells' bounding box [cells, inclusive]; empty while x0 > x1.
struct Box {
  int x0, y0, x1 = -1, y1 = -1;
  bool empty() const { return x0 > x1; }
  void add(int x, int y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  long area() const { return empty() ? 0 : static_cast<long>(x1 - x0 + 1) * (y1 - y0 + 1); }
  void add(const Box& b) {
    add(b.x0, b.y0);
    add(b.x1, b.y1);
  }
};
}  // namespace

GridWindow frameCells(const OccupancyImage& image) {
  if (image.resolution <= 0.0) return GridWindow{0, 0, image.width, image.height};
  return GridWindow{static_cast<int>(std::floor(image.origin.x() / image.resolution + 1e-6)),
                    static_cast<int>(std::floor(image.origin.y() / image.resolution + 1e-6)), image.width, image.height};
}

OccupancyImage paddedToBlocks(OccupancyImage image, int block_cells, const GridWindow* cover) {
  if (block_cells < 1) throw std::invalid_argument("paddedToBlocks: block_cells must be at least 1");
  if (image.width <= 0 || image.height <= 0 || image.resolution <= 0.0) return image;
  const GridWindow own = frameCells(image);
  // The padded window in the frame's cells: [x0, x1) x [y0, y1).
  int x0 = floorDiv(own.x, block_cells) * block_cells, y0 = floorDiv(own.y, block_cells) * block_cells;
  int x1 = -floorDiv(-(own.x + own.width), block_cells) * block_cells;
  int y1 = -floorDiv(-(own.y + own.height), block_cells) * block_cells;
  if (cover && cover->width > 0 && cover->height > 0) {
    x0 = std::min(x0, cover->x);
    y0 = std::min(y0, cover->y);
    x1 = std::max(x1, cover->x + cover->width);
    y1 = std::max(y1, cover->y + cover->height);
  }
  const int left = own.x - x0, bottom = own.y - y0, width = x1 - x0, height = y1 - y0;
  if (left == 0 && bottom == 0 && width == image.width && height == image.height) return image;
  OccupancyImage out;
  out.width = width;
  out.height = height;
  out.resolution = image.resolution;
  out.origin = image.origin - Eigen::Vector2d(left, bottom) * image.resolution;
  out.data.assign(static_cast<size_t>(width) * height, int8_t{-1});
  for (int r = 0; r < image.height; ++r) {
    std::copy_n(image.data.begin() + static_cast<size_t>(r) * image.width, image.width,
                out.data.begin() + static_cast<size_t>(r + bottom) * width + left);
  }
  return out;
}

std::vector<GridWindow> changedWindows(const std::vector<int8_t>& before, const std::vector<int8_t>& after, int width,
                                       int height, int tile) {
  if (tile < 1) throw std::invalid_argument("changedWindows: tile must be at least 1");
  if (width < 0 || height < 0 || before.size() != static_cast<size_t>(width) * height || after.size() != before.size()) {
    throw std::invalid_argument("changedWindows: the grids are not both width x height cells");
  }
  std::vector<GridWindow> out;
  const int tiles_x = (width + tile - 1) / tile;
  for (int ty = 0; ty * tile < height; ++ty) {
    const int row0 = ty * tile, row1 = std::min(height, row0 + tile);
    std::vector<Box> box(tiles_x, Box{width, height});  // per tile of this row of tiles
    for (int r = row0; r < row1; ++r) {
      const int8_t* b = before.data() + static_cast<size_t>(r) * width;
      const int8_t* a = after.data() + static_cast<size_t>(r) * width;
      for (int c = 0; c < width; ++c) {
        if (a[c] != b[c]) box[c / tile].add(c, r);
      }
    }
    for (int tx = 0; tx < tiles_x;) {
      if (box[tx].empty()) {
        ++tx;
        continue;
      }
      Box run = box[tx];
      long cost = run.area() + kWindowCost;  // of the run's windows sent one by one
      for (++tx; tx < tiles_x && !box[tx].empty(); ++tx) {
        Box joined = run;
        joined.add(box[tx]);
        if (joined.area() > cost + box[tx].area()) break;  // more unchanged cells than a window costs
        cost += box[tx].area() + kWindowCost;
        run = joined;
      }
      out.push_back(GridWindow{run.x0, run.y0, run.x1 - run.x0 + 1, run.y1 - run.y0 + 1});
    }
  }
  return out;
}

bool MapUpdateLog::update(MapUpdate u) {
  if (u.stamp_ns == 0) return has_whole_;
  if (has_whole_ && u.stamp_ns <= whole_stamp_ns_) return false;
  held_bytes_ += u.data.size();
  held_.push_back(std::move(u));
  while (!held_.empty() && (held_.size() > max_held_ || held_bytes_ > max_bytes_)) {
    held_bytes_ -= held_.front().data.size();
    held_.pop_front();
  }
  return has_whole_;
}

std::optional<std::vector<MapUpdate>> MapUpdateLog::whole(int64_t stamp_ns, int64_t now_ns) {
  if (has_whole_ && stamp_ns < whole_stamp_ns_) {
    if (stamp_ns != 0 && now_ns >= whole_stamp_ns_) return std::nullopt;
    held_.clear();
  }
  has_whole_ = true;
  whole_stamp_ns_ = stamp_ns;
  std::vector<MapUpdate> newer;
  std::deque<MapUpdate> kept;
  held_bytes_ = 0;
  for (auto& u : held_) {
    if (u.stamp_ns <= stamp_ns) continue;
    held_bytes_ += u.data.size();
    newer.push_back(u);
    kept.push_back(std::move(u));
  }
  held_ = std::move(kept);
  return newer;
}

}  // namespace core
}  // namespace mbot
