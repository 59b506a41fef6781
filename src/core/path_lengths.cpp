#include "mbot_slam_navigation/core/path_lengths.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace mbot {
namespace core {

namespace {

void checkGrid(const char* what, const std::vector<uint8_t>& passable, int width, int height) {
  if (width <= 0 || height <= 0 || passable.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument(std::string(what) + ": passable has " + std::to_string(passable.size()) +
                                " cells, not " + std::to_string(width) + " x " + std::to_string(height));
  }
}

void checkCell(const char* what, const Cell& c, int width, int height) {
  if (c.x < 0 || c.y < 0 || c.x >= width || c.y >= height) {
    throw std::invalid_argument(std::string(what) + ": cell (" + std::to_string(c.x) + ", " + std::to_string(c.y) +
                                ") lies outside the " + std::to_string(width) + " x " + std::to_string(height) +
                                " grid");
  }
}

// Dijkstra over a copy of the grid with a blocked border one cell wide (no bounds checks per step),
// run from one start after another with its buffers kept: a run resets only the cells it touched.
//
// Dial's bucket queue instead of a heap: cells whose length lies in [b, b + 1) share bucket b.
// Every step is at least 1 long, so no cell of bucket b can shorten another one of bucket b: a
// bucket is final when it is reached, in any order. A step is at most sqrt(2), so it lands in
// bucket b + 1 or b + 2, and three buckets in turn hold everything pending.
class Search {
 public:
  Search(const std::vector<uint8_t>& passable, int width, int height)
      : w_(width), h_(height), pw_(width + 2), open_(static_cast<std::size_t>(pw_) * (height + 2), 0),
        dist_(open_.size(), -1.0f), settled_(open_.size(), 0), wanted_(open_.size(), 0) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) open_[index(Cell{x, y})] = passable[y * width + x] != 0;
    }
  }

  int index(const Cell& c) const { return (c.y + 1) * pw_ + c.x + 1; }
  void open(const Cell& c) { open_[index(c)] = 1; }
  bool settled(int i) const { return settled_[i] != 0; }
  float dist(int i) const { return dist_[i]; }

  /// Path lengths from `start` until every cell of `stop_when` (padded indices) is settled, or
  /// everything reachable is. Cells not settled keep -1.
  void run(const Cell& start, const std::vector<int>& stop_when = {}) {
    reset();
    std::size_t waiting_for = stop_when.size();
    for (int t : stop_when) ++wanted_[t];
    const int s = index(start);
    dist_[s] = 0.0f;
    touched_.push_back(s);
    buckets_[0].push_back(s);
    std::size_t pending = 1;
    const float diag = std::sqrt(2.0f);
    const int straight[4] = {-1, 1, -pw_, pw_};
    // a diagonal step and the two side cells it needs free (no squeezing past a corner)
    const int diagonal[4][3] = {{-pw_ - 1, -pw_, -1}, {-pw_ + 1, -pw_, 1}, {pw_ - 1, pw_, -1}, {pw_ + 1, pw_, 1}};
    auto relax = [&](int j, float nd) {
      if (dist_[j] < 0.0f || nd < dist_[j]) {
        if (dist_[j] < 0.0f) touched_.push_back(j);
        dist_[j] = nd;
        buckets_[static_cast<long>(nd) % 3].push_back(j);
        ++pending;
      }
    };
    for (long b = 0; pending > 0; ++b) {
      std::vector<int>& here = buckets_[b % 3];
      for (std::size_t q = 0; q < here.size(); ++q) {  // relax() never appends to this bucket
        const int i = here[q];
        --pending;
        if (settled_[i] || static_cast<long>(dist_[i]) != b) continue;  // shortened since, or seen
        settled_[i] = 1;
        waiting_for -= wanted_[i];
        const float d = dist_[i];
        for (int k = 0; k < 4; ++k) {
          if (open_[i + straight[k]]) relax(i + straight[k], d + 1.0f);
        }
        for (int k = 0; k < 4; ++k) {
          if (open_[i + diagonal[k][0]] && open_[i + diagonal[k][1]] && open_[i + diagonal[k][2]]) {
            relax(i + diagonal[k][0], d + diag);
          }
        }
      }
      here.clear();
      if (!stop_when.empty() && waiting_for == 0) break;
    }
    for (auto& bucket : buckets_) bucket.clear();
    for (int t : stop_when) wanted_[t] = 0;
    for (int i : touched_) {
      if (!settled_[i]) dist_[i] = -1.0f;  // reached, not final: not known
    }
  }

  void copyTo(std::vector<float>& out) const {
    out.resize(static_cast<std::size_t>(w_) * h_);
    for (int y = 0; y < h_; ++y) {
      std::copy(dist_.begin() + (y + 1) * pw_ + 1, dist_.begin() + (y + 1) * pw_ + 1 + w_, out.begin() + y * w_);
    }
  }

 private:
  void reset() {
    for (int i : touched_) {
      dist_[i] = -1.0f;
      settled_[i] = 0;
    }
    touched_.clear();
  }

  int w_, h_, pw_;
  std::vector<uint8_t> open_;
  std::vector<float> dist_;
  std::vector<uint8_t> settled_;
  std::vector<uint16_t> wanted_;  // how many of the cells a run stops for are this one
  std::vector<int> touched_;
  std::vector<int> buckets_[3];
};

}  // namespace

std::vector<float> pathLengths(const std::vector<uint8_t>& passable, int width, int height, const Cell& start) {
  checkGrid("pathLengths", passable, width, height);
  checkCell("pathLengths: start", start, width, height);
  Search search(passable, width, height);
  search.run(start);
  std::vector<float> dist;
  search.copyTo(dist);
  return dist;
}

std::vector<double> pathLengthsBetween(const std::vector<uint8_t>& passable, int width, int height,
                                       const std::vector<Cell>& cells) {
  checkGrid("pathLengthsBetween", passable, width, height);
  for (const Cell& c : cells) checkCell("pathLengthsBetween", c, width, height);
  const std::size_t n = cells.size();
  std::vector<double> d(n * n, -1.0);
  if (n == 0) return d;
  Search search(passable, width, height);
  std::vector<int> at(n);
  for (std::size_t i = 0; i < n; ++i) {
    search.open(cells[i]);
    at[i] = search.index(cells[i]);
  }
  // From each cell to the ones after it (the grid is searched both ways alike, so d is symmetric),
  // each search stopping when those are settled: the goals of an exploration's tour lie near the
  // robot, and a search over the whole floor of a building for each would cost 20 times that.
  for (std::size_t i = 0; i < n; ++i) {
    d[i * n + i] = 0.0;
    if (i + 1 == n) break;
    search.run(cells[i], std::vector<int>(at.begin() + i + 1, at.end()));
    for (std::size_t j = i + 1; j < n; ++j) {
      const float v = search.settled(at[j]) ? search.dist(at[j]) : -1.0f;
      d[i * n + j] = d[j * n + i] = v;
    }
  }
  return d;
}

}  // namespace core
}  // namespace mbot
