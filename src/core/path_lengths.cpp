#include "mbot_slam_navigation/core/path_lengths.h"

#include <algorithm>
#include <cmath>
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
  // Dijkstra on a copy with a blocked border one cell wide: no bounds checks per step (this runs a
  // few times per exploration cycle over the whole floor, 0.14 M cells on the office).
  const int pw = width + 2;
  std::vector<uint8_t> open_cell(static_cast<std::size_t>(pw) * (height + 2), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) open_cell[(y + 1) * pw + x + 1] = passable[y * width + x] != 0;
  }
  std::vector<float> padded(open_cell.size(), -1.0f);
  std::vector<uint8_t> settled(open_cell.size(), 0);
  // Dial's bucket queue instead of a heap: cells whose length lies in [b, b + 1) share bucket b.
  // Every step is at least 1 long, so no cell of bucket b can shorten another one of bucket b: a
  // bucket is final when it is reached, in any order. A step is at most sqrt(2), so it lands in
  // bucket b + 1 or b + 2, and three buckets in turn hold everything pending.
  std::vector<int> buckets[3];
  const int s = (start.y + 1) * pw + start.x + 1;
  padded[s] = 0.0f;
  buckets[0].push_back(s);
  std::size_t pending = 1;
  const float diag = std::sqrt(2.0f);
  const int straight[4] = {-1, 1, -pw, pw};
  // a diagonal step and the two side cells it needs free (no squeezing past a corner)
  const int diagonal[4][3] = {{-pw - 1, -pw, -1}, {-pw + 1, -pw, 1}, {pw - 1, pw, -1}, {pw + 1, pw, 1}};
  auto relax = [&](int j, float nd) {
    if (padded[j] < 0.0f || nd < padded[j]) {
      padded[j] = nd;
      buckets[static_cast<long>(nd) % 3].push_back(j);
      ++pending;
    }
  };
  for (long b = 0; pending > 0; ++b) {
    std::vector<int>& here = buckets[b % 3];
    for (std::size_t q = 0; q < here.size(); ++q) {  // relax() never appends to this bucket
      const int i = here[q];
      --pending;
      if (settled[i] || static_cast<long>(padded[i]) != b) continue;  // shortened since, or seen
      settled[i] = 1;
      const float d = padded[i];
      for (int k = 0; k < 4; ++k) {
        if (open_cell[i + straight[k]]) relax(i + straight[k], d + 1.0f);
      }
      for (int k = 0; k < 4; ++k) {
        if (open_cell[i + diagonal[k][0]] && open_cell[i + diagonal[k][1]] && open_cell[i + diagonal[k][2]]) {
          relax(i + diagonal[k][0], d + diag);
        }
      }
    }
    here.clear();
  }
  std::vector<float> dist(passable.size());
  for (int y = 0; y < height; ++y) {
    std::copy(padded.begin() + (y + 1) * pw + 1, padded.begin() + (y + 1) * pw + 1 + width, dist.begin() + y * width);
  }
  return dist;
}

}  // namespace core
}  // namespace mbot
