#include "mbot_slam_navigation/core/path_lengths.h"

#include <cmath>
#include <functional>
#include <queue>
#include <stdexcept>
#include <string>
#include <utility>

namespace mbot {
namespace core {

std::vector<float> pathLengths(const std::vector<uint8_t>& passable, int width, int height, const Cell& start) {
  if (width <= 0 || height <= 0 || passable.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("pathLengths: passable has " + std::to_string(passable.size()) + " cells, not " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  if (start.x < 0 || start.y < 0 || start.x >= width || start.y >= height) {
    throw std::invalid_argument("pathLengths: start cell (" + std::to_string(start.x) + ", " +
                                std::to_string(start.y) + ") lies outside the grid");
  }
  std::vector<float> dist(passable.size(), -1.0f);
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  const int s = start.y * width + start.x;
  dist[s] = 0.0f;
  open.push({0.0f, s});
  const float diag = std::sqrt(2.0f);
  auto free_at = [&](int x, int y) { return x >= 0 && y >= 0 && x < width && y < height && passable[y * width + x]; };
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;  // a stale entry: the cell was reached shorter since
    const int x = i % width, y = i / width;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !free_at(x + dx, y + dy)) continue;
        // A diagonal step needs both side cells free, or the path would squeeze past a corner.
        if (dx != 0 && dy != 0 && !(free_at(x + dx, y) && free_at(x, y + dy))) continue;
        const int j = (y + dy) * width + x + dx;
        const float nd = d + ((dx != 0 && dy != 0) ? diag : 1.0f);
        if (dist[j] < 0.0f || nd < dist[j]) {
          dist[j] = nd;
          open.push({nd, j});
        }
      }
    }
  }
  return dist;
}

}  // namespace core
}  // namespace mbot
