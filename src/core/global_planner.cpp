#include "mbot_slam_navigation/core/global_planner.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <utility>

namespace mbot {
namespace core {
namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
using Entry = std::pair<float, int>;
using MinHeap = std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>>;
}  // namespace

const char* toString(PlanStatus s) {
  switch (s) {
    case PlanStatus::kOk: return "ok";
    case PlanStatus::kStartOffMap: return "start off the costmap";
    case PlanStatus::kGoalOffMap: return "goal off the costmap";
    case PlanStatus::kStartOccupied: return "start occupied";
    case PlanStatus::kGoalOccupied: return "goal occupied";
    case PlanStatus::kNoPath: return "no path";
  }
  return "?";
}

GlobalPlanner::GlobalPlanner(const PlannerParams& params) : params_(params) {
  for (int v = 0; v < 256; ++v) {
    if (v < cost::kInscribed) cost_of_value_[v] = static_cast<float>(params_.neutral_cost + params_.cost_factor * v);
    else if (v == cost::kNoInformation && params_.allow_unknown) cost_of_value_[v] = static_cast<float>(cost::kInscribed);
    else cost_of_value_[v] = kInf;
  }
}

Plan GlobalPlanner::makePlan(const Costmap& map, const Eigen::Vector2d& start_m, const Eigen::Vector2d& goal_m) {
  Plan plan;
  const Cell s = map.worldToCell(start_m), g = map.worldToCell(goal_m);
  std::ostringstream why;
  auto fail = [&](PlanStatus status) {
    plan.status = status;
    plan.message = why.str();
    plan.path.clear();
    return plan;
  };
  if (!map.contains(s)) {
    why << "the start (" << start_m.x() << ", " << start_m.y() << ") is off the costmap";
    return fail(PlanStatus::kStartOffMap);
  }
  if (!map.contains(g)) {
    why << "the goal (" << goal_m.x() << ", " << goal_m.y() << ") is off the costmap";
    return fail(PlanStatus::kGoalOffMap);
  }
  if (map.cost(s) == cost::kLethal) {
    why << "the start (" << start_m.x() << ", " << start_m.y() << ") is in a lethal cell";
    return fail(PlanStatus::kStartOccupied);
  }
  const std::size_t n = map.costs().size();
  if (value_.size() != n) {
    value_.assign(n, kInf);
    stamp_.assign(n, 0);
    done_.assign(n, 0);
    parent_.assign(n, -1);
    generation_ = 0;
  }
  if (++generation_ == 0) {  // wrapped around: clear once every 2^32 searches
    std::fill(stamp_.begin(), stamp_.end(), 0);
    generation_ = 1;
  }
  costs_ = &map.costs();
  const int start = static_cast<int>(map.index(s));
  start_ = start;
  // The robot's own cell is passable even when inscribed (navfn clears the robot cell).
  start_cost_ = static_cast<float>(params_.neutral_cost);

  int goal = static_cast<int>(map.index(g));
  if (!std::isfinite(cellCost(goal))) {
    // default_tolerance: the nearest traversable cell to the goal within that distance.
    const int r = static_cast<int>(std::floor(params_.default_tolerance / map.resolution()));
    int best = -1;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const Cell c{g.x + dx, g.y + dy};
        const double d2 = double(dx) * dx + double(dy) * dy;
        if (d2 > double(r) * r || !map.contains(c) || !std::isfinite(cellCost(static_cast<int>(map.index(c))))) continue;
        if (d2 < best_d2) {
          best_d2 = d2;
          best = static_cast<int>(map.index(c));
        }
      }
    }
    if (best < 0) {
      why << "the goal (" << goal_m.x() << ", " << goal_m.y() << ") is in an obstacle or its inflation, and no free cell lies within default_tolerance "
          << params_.default_tolerance << " m";
      return fail(PlanStatus::kGoalOccupied);
    }
    goal = best;
  }
  plan.goal = map.cellCenter({goal % map.width(), goal / map.width()});
  const bool found = params_.use_astar ? searchAStar(map, start, goal, plan) : search(map, start, goal, plan);
  if (!found) {
    why << "no path from (" << start_m.x() << ", " << start_m.y() << ") to (" << plan.goal.x() << ", " << plan.goal.y()
        << ") avoids the obstacles" << (params_.allow_unknown ? "" : " through known space (allow_unknown is false)");
    return fail(PlanStatus::kNoPath);
  }
  plan.status = PlanStatus::kOk;
  return plan;
}

bool GlobalPlanner::search(const Costmap& map, int start, int goal, Plan& plan) {
  const int w = map.width(), h = map.height();
  // done_ is valid where stamp_ is current; a cell is done once popped.
  auto isDone = [&](int i) { return stamp_[i] == generation_ && done_[i]; };
  MinHeap open;
  setValue(goal, 0.0f);
  done_[goal] = 0;
  open.push({0.0f, goal});
  bool reached = false;
  while (!open.empty()) {
    const auto [p, i] = open.top();
    open.pop();
    if (isDone(i) || p > value(i)) continue;
    done_[i] = 1;
    ++plan.expanded;
    if (i == start) {
      reached = true;
      break;
    }
    const int x = i % w, y = i / w;
    const int nb[4] = {x > 0 ? i - 1 : -1, x < w - 1 ? i + 1 : -1, y > 0 ? i - w : -1, y < h - 1 ? i + w : -1};
    for (int k : nb) {
      if (k < 0 || isDone(k)) continue;
      const float hf = cellCost(k);
      if (!std::isfinite(hf)) continue;
      // navfn's quadratic update from the two axes' smallest neighbours.
      const int kx = k % w, ky = k / w;
      const float ta = std::min(kx > 0 ? value(k - 1) : kInf, kx < w - 1 ? value(k + 1) : kInf);
      const float tc = std::min(ky > 0 ? value(k - w) : kInf, ky < h - 1 ? value(k + w) : kInf);
      const float lo = std::min(ta, tc), hi = std::max(ta, tc);
      float pot;
      if (!std::isfinite(hi) || hi - lo >= hf) {
        pot = lo + hf;
      } else {
        const float d = (hi - lo) / hf;
        pot = lo + hf * (-0.2301f * d * d + 0.5307f * d + 0.7040f);
      }
      if (pot < value(k)) {
        if (stamp_[k] != generation_) done_[k] = 0;
        setValue(k, pot);
        open.push({pot, k});
      }
    }
  }
  if (!reached) return false;
  // Descend the potential from the start (8-connected), to the goal.
  int i = start;
  plan.path.push_back(map.cellCenter({i % w, i / w}));
  for (std::size_t steps = 0; i != goal && steps < value_.size(); ++steps) {
    const int x = i % w, y = i / w;
    int best = -1;
    float best_p = value(i);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || x + dx < 0 || y + dy < 0 || x + dx >= w || y + dy >= h) continue;
        const int k = i + dy * w + dx;
        if (cutsCorner(i, dx, dy, w)) continue;
        if (value(k) < best_p) {
          best_p = value(k);
          best = k;
        }
      }
    }
    if (best < 0) return false;  // a local minimum: cannot happen with a wavefront from the goal
    i = best;
    plan.path.push_back(map.cellCenter({i % w, i / w}));
  }
  return i == goal;
}

bool GlobalPlanner::searchAStar(const Costmap& map, int start, int goal, Plan& plan) {
  const int w = map.width(), h = map.height();
  const float neutral = static_cast<float>(params_.neutral_cost);
  const int gx = goal % w, gy = goal / w;
  auto heuristic = [&](int i) { return neutral * std::hypot(float(i % w - gx), float(i / w - gy)); };
  auto isDone = [&](int i) { return stamp_[i] == generation_ && done_[i]; };
  MinHeap open;
  setValue(start, 0.0f);
  done_[start] = 0;
  parent_[start] = -1;
  open.push({heuristic(start), start});
  const float diag = std::sqrt(2.0f);
  bool reached = false;
  while (!open.empty()) {
    const int i = open.top().second;
    open.pop();
    if (isDone(i)) continue;
    done_[i] = 1;
    ++plan.expanded;
    if (i == goal) {
      reached = true;
      break;
    }
    const int x = i % w, y = i / w;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || x + dx < 0 || y + dy < 0 || x + dx >= w || y + dy >= h) continue;
        const int k = i + dy * w + dx;
        if (isDone(k)) continue;
        const float ck = cellCost(k);
        if (!std::isfinite(ck)) continue;
        if (cutsCorner(i, dx, dy, w)) continue;
        const float g = value(i) + ck * (dx != 0 && dy != 0 ? diag : 1.0f);
        if (g < value(k)) {
          if (stamp_[k] != generation_) done_[k] = 0;
          setValue(k, g);
          parent_[k] = i;
          open.push({g + heuristic(k), k});
        }
      }
    }
  }
  if (!reached) return false;
  for (int i = goal; i >= 0; i = parent_[i]) plan.path.push_back(map.cellCenter({i % w, i / w}));
  std::reverse(plan.path.begin(), plan.path.end());
  return true;
}

}  // namespace core
}  // namespace mbot
