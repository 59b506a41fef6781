#include "mbot_slam_navigation/core/tour.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace mbot {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// dp[mask * n + e]: the shortest path through the goals of mask that ends at e; by symmetry the
// shortest path through all goals that begins at e is dp[full * n + e].
std::vector<double> exactTours(const std::vector<double>& d, int n) {
  const std::size_t full = (std::size_t{1} << n) - 1;
  std::vector<double> dp((full + 1) * n, kInf);
  for (int i = 0; i < n; ++i) dp[(std::size_t{1} << i) * n + i] = 0.0;
  for (std::size_t mask = 1; mask < full; ++mask) {
    for (int e = 0; e < n; ++e) {
      const double here = dp[mask * n + e];
      if (!(mask >> e & 1) || here == kInf) continue;
      for (int j = 0; j < n; ++j) {
        if (mask >> j & 1) continue;
        double& next = dp[(mask | std::size_t{1} << j) * n + j];
        next = std::min(next, here + d[e * n + j]);
      }
    }
  }
  return std::vector<double>(dp.begin() + full * n, dp.end());
}

double pathLength(const std::vector<double>& d, int n, const std::vector<int>& p) {
  double sum = 0.0;
  for (std::size_t k = 1; k < p.size(); ++k) sum += d[p[k - 1] * n + p[k]];
  return sum;
}

// A short open path from `start` through all goals: nearest neighbour first, then 2-opt moves
// (reverse a stretch) and segment moves (take a stretch out and put it elsewhere, either way
// round: or-opt with stretches of any length, which turns "the near side, then back across to
// the far side" into "the far side first" when that is shorter) while one shortens it by more
// than rounding. The start stays first.
double heuristicTour(const std::vector<double>& d, int n, int start) {
  std::vector<int> p{start};
  std::vector<bool> used(n, false);
  used[start] = true;
  for (int k = 1; k < n; ++k) {
    int best = -1;
    for (int j = 0; j < n; ++j) {
      if (!used[j] && (best < 0 || d[p.back() * n + j] < d[p.back() * n + best])) best = j;
    }
    used[best] = true;
    p.push_back(best);
  }
  auto D = [&](int a, int b) { return d[a * n + b]; };
  const double eps = 1e-9;
  std::vector<int> rest;
  for (int pass = 0; pass < 50; ++pass) {
    bool improved = false;
    // 2-opt: reverse p[a..b]; the edge after b is absent when b is the end of the path.
    for (int a = 1; a + 1 < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        double delta = D(p[a - 1], p[b]) - D(p[a - 1], p[a]);
        if (b + 1 < n) delta += D(p[a], p[b + 1]) - D(p[b], p[b + 1]);
        if (delta < -eps) {
          std::reverse(p.begin() + a, p.begin() + b + 1);
          improved = true;
        }
      }
    }
    // Segment moves: p[a..b] out, then in between rest[c - 1] and rest[c] (or at the end).
    for (int a = 1; a < n; ++a) {
      for (int b = a; b < n; ++b) {
        const double removed = D(p[a - 1], p[a]) + (b + 1 < n ? D(p[b], p[b + 1]) - D(p[a - 1], p[b + 1]) : 0.0);
        rest.assign(p.begin(), p.begin() + a);
        rest.insert(rest.end(), p.begin() + b + 1, p.end());
        const int m = static_cast<int>(rest.size());
        int best_c = -1;
        bool best_reversed = false;
        double best_gain = eps;
        for (int c = 1; c <= m; ++c) {
          if (c == a) continue;  // where it was
          const double bridge = c < m ? D(rest[c - 1], rest[c]) : 0.0;
          const double forward = D(rest[c - 1], p[a]) + (c < m ? D(p[b], rest[c]) : 0.0) - bridge;
          const double backward = D(rest[c - 1], p[b]) + (c < m ? D(p[a], rest[c]) : 0.0) - bridge;
          if (removed - forward > best_gain) best_gain = removed - forward, best_c = c, best_reversed = false;
          if (removed - backward > best_gain) best_gain = removed - backward, best_c = c, best_reversed = true;
        }
        if (best_c < 0) continue;
        std::vector<int> seg(p.begin() + a, p.begin() + b + 1);
        if (best_reversed) std::reverse(seg.begin(), seg.end());
        rest.insert(rest.begin() + best_c, seg.begin(), seg.end());
        p.swap(rest);
        improved = true;
      }
    }
    if (!improved) break;
  }
  return pathLength(d, n, p);
}

}  // namespace

std::vector<double> shortestPathsThroughAll(const std::vector<double>& d, int n, int exact_max) {
  if (n < 0 || d.size() != static_cast<std::size_t>(n) * n) {
    throw std::invalid_argument("shortestPathsThroughAll: " + std::to_string(d.size()) + " distances for " +
                                std::to_string(n) + " goals (needs n x n)");
  }
  for (double v : d) {
    if (!std::isfinite(v) || v < 0.0) {
      throw std::invalid_argument("shortestPathsThroughAll: distance " + std::to_string(v) +
                                  " (needs finite, >= 0; give unconnected goals a long detour)");
    }
  }
  if (n == 0) return {};
  // Never exact beyond 16 goals, whatever exact_max says: the table is 2^n x n (8 MB at 16, 160 MB at 20).
  if (n <= std::min(exact_max, 16)) return exactTours(d, n);
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) out[i] = heuristicTour(d, n, i);
  return out;
}

}  // namespace core
}  // namespace mbot
