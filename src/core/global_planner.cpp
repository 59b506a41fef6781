#include "mbot_slam_navigation/core/global_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace mbot {
namespace core {
namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
// Open-list entry: `key` orders it, `depth` is the cost so far (stale entries are recognised by it).
struct Entry {
  float key;
  float depth;
  int cell;
};
// A bucket queue (Dial's), hand-written as no library has one: keys fall into buckets `width` wide,
// taken in order, each as a stack (the newest first: among equal keys the search goes on from the
// cell nearest its end instead of widening). Pushes and pops are O(1), against a binary heap's
// O(log n) with a cache miss per level, which took 40% of a plan. Keys are exact to `width`
// (1/50 of a free cell's cost here), and a consistent search never pushes a key more than `span`
// above the smallest one in the queue, so a ring of span / width buckets is enough.
class BucketQueue {
 public:
  BucketQueue(float width, float span)
      : width_(width), buckets_(static_cast<std::size_t>(std::ceil(span / width)) + 2) {}
  bool empty() const { return size_ == 0; }
  void push(const Entry& e) {
    long index = static_cast<long>(std::floor(e.key / width_));
    if (!started_) {  // afterwards keys never fall below the last popped one (up to rounding)
      current_ = index;
      started_ = true;
    }
    // A key below the current bucket (float rounding) or past the ring (a search that is not
    // consistent) goes to the nearest bucket that keeps the ring valid.
    index = std::max(index, current_);
    index = std::min(index, current_ + static_cast<long>(buckets_.size()) - 1);
    buckets_[static_cast<std::size_t>(index) % buckets_.size()].push_back(e);
    ++size_;
  }
  Entry pop() {
    for (;;) {
      auto& b = buckets_[static_cast<std::size_t>(current_) % buckets_.size()];
      if (!b.empty()) {
        const Entry e = b.back();
        b.pop_back();
        --size_;
        return e;
      }
      ++current_;
    }
  }

 private:
  float width_;
  std::vector<std::vector<Entry>> buckets_;
  long current_ = 0;
  bool started_ = false;
  std::size_t size_ = 0;
};
// The binary heap of before, kept as the reference of use_bounds false (benchmarks compare with it).
class HeapQueue {
 public:
  HeapQueue(float, float) {}
  bool empty() const { return heap_.empty(); }
  void push(const Entry& e) { heap_.push(e); }
  Entry pop() {
    const Entry e = heap_.top();
    heap_.pop();
    return e;
  }

 private:
  struct Later {
    bool operator()(const Entry& a, const Entry& b) const { return a.key > b.key; }
  };
  std::priority_queue<Entry, std::vector<Entry>, Later> heap_;
};

// The quadratic potential grows by at least 0.704 * cost per 4-connected step (navfn's update with
// equal neighbours), and a displacement takes at least its octile length in such steps: the octile
// bound times this is a lower bound of the potential still to come.
constexpr float kPotentialBoundScale = 0.70f;

// The octile distance of an offset (|dx|, |dy|) in steps: the shortest 8-connected path on a free grid.
float octile(int ax, int ay) { return std::max(ax, ay) + (std::sqrt(2.0f) - 1.0f) * std::min(ax, ay); }
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

GlobalPlanner::GlobalPlanner(const PlannerParams& params) : params_(params) { setLethalCost(params.lethal_cost); }

void GlobalPlanner::setLethalCost(int lethal_cost) {
  if (lethal_cost < 1 || lethal_cost > cost::kInscribed) {
    throw std::invalid_argument("lethal_cost must be in 1..253, got " + std::to_string(lethal_cost));
  }
  params_.lethal_cost = lethal_cost;
  for (int v = 0; v < 256; ++v) {
    if (v < params_.lethal_cost) cost_of_value_[v] = static_cast<float>(params_.neutral_cost + params_.cost_factor * v);
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
  nextGeneration();
  costs_ = &map.costs();
  const int start = static_cast<int>(map.index(s));
  start_ = start;
  // The robot's own cell is passable even when inscribed (navfn clears the robot cell), and so are
  // the blocked cells near a blocked start (kStartEscape_m), at the highest passable cost.
  start_cost_ = static_cast<float>(params_.neutral_cost);
  map_width_ = map.width();
  start_x_ = s.x;
  start_y_ = s.y;
  const uint8_t start_value = map.cost(s);
  escape_cells_ = start_value >= params_.lethal_cost && start_value <= cost::kInscribed
                      ? static_cast<int>(std::ceil(kStartEscape_m / map.resolution()))
                      : 0;
  escape_cost_ = cost_of_value_[params_.lethal_cost - 1];

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
  width_ = map.width();
  height_ = map.height();
  corridor_active_ = false;
  auto fine = [&]() {
    plan.path.clear();
    if (!params_.use_bounds) {
      return params_.use_astar ? searchAStar<HeapQueue>(map, start, goal, plan) : search<HeapQueue>(map, start, goal, plan);
    }
    return params_.use_astar ? searchAStar<BucketQueue>(map, start, goal, plan) : search<BucketQueue>(map, start, goal, plan);
  };
  bool found = false;
  if (params_.use_bounds) {
    // The coarse plan connects any two neighbouring blocks that hold a traversable cell, so no
    // coarse path means no path at all.
    if (coarsePlan(start, goal, plan)) {
      for (int radius : {kCorridorRadius, 4 * kCorridorRadius}) {
        markCorridor(radius);
        corridor_active_ = true;
        found = fine();
        if (found) break;
        nextGeneration();  // a wall inside a block the coarse level let through: try wider
      }
      corridor_active_ = false;
      if (!found) found = fine();
    }
  } else {
    found = fine();
  }
  if (!found) {
    why << "no path from (" << start_m.x() << ", " << start_m.y() << ") to (" << plan.goal.x() << ", " << plan.goal.y()
        << ") avoids the obstacles" << (params_.allow_unknown ? "" : " through known space (allow_unknown is false)");
    return fail(PlanStatus::kNoPath);
  }
  plan.status = PlanStatus::kOk;
  return plan;
}

float GlobalPlanner::blockCost(int bx, int by) {
  const std::size_t b = static_cast<std::size_t>(by) * bw_ + bx;
  if (block_stamp_[b] == generation_) return block_cost_[b];
  const int w = width_;
  const int x0 = bx * kBlock, y0 = by * kBlock;
  const int x1 = std::min(x0 + kBlock, w), y1 = std::min(y0 + kBlock, height_);
  const uint8_t* c = costs_->data();
  float sum = 0.0f;
  int passable = 0;
  for (int y = y0; y < y1; ++y) {
    const uint8_t* row = c + static_cast<std::size_t>(y) * w;
    for (int x = x0; x < x1; ++x) {
      float v = cost_of_value_[row[x]];
      if (escape_cells_ > 0 && !std::isfinite(v)) v = cellCost(y * w + x);
      if (std::isfinite(v)) {
        sum += v;
        ++passable;
      }
    }
  }
  // The start's cell may be inscribed and still passable; the goal's is passable by construction.
  const bool ends = coarse_start_ == static_cast<int>(b) || coarse_goal_ == static_cast<int>(b);
  block_stamp_[b] = generation_;
  block_done_[b] = 0;
  block_cost_[b] = passable ? sum / passable : (ends ? static_cast<float>(params_.neutral_cost) : kInf);
  return block_cost_[b];
}

bool GlobalPlanner::coarsePlan(int start, int goal, Plan& plan) {
  const int w = width_;
  bw_ = (w + kBlock - 1) / kBlock;
  bh_ = (height_ + kBlock - 1) / kBlock;
  const std::size_t nb = static_cast<std::size_t>(bw_) * bh_;
  if (block_cost_.size() != nb) {
    block_cost_.assign(nb, kInf);
    block_stamp_.assign(nb, 0);
    block_g_.assign(nb, kInf);
    block_parent_.assign(nb, -1);
    block_done_.assign(nb, 0);
    corridor_.assign(nb, 0);
    corridor_gen_ = 0;
  }
  auto blockOf = [&](int cell) { return (cell / w) / kBlock * bw_ + (cell % w) / kBlock; };
  coarse_start_ = blockOf(start);
  coarse_goal_ = blockOf(goal);
  const int gbx = coarse_goal_ % bw_, gby = coarse_goal_ / bw_;
  const float neutral = static_cast<float>(params_.neutral_cost) * kBlock;
  auto heuristic = [&](int b) {
    return neutral * octile(std::abs(b % bw_ - gbx), std::abs(b / bw_ - gby));
  };
  // block_done_: 0 unseen, 1 open, 2 closed; reset by blockCost when it first sees a block in a search.
  // Keys grow by at most two steps' cost (a consistent heuristic changes by at most one step).
  BucketQueue open(1.0f, 2.0f * static_cast<float>(kBlock) * std::sqrt(2.0f) * cost::kInscribed);
  blockCost(coarse_start_ % bw_, coarse_start_ / bw_);
  block_g_[coarse_start_] = 0.0f;
  block_done_[coarse_start_] = 1;
  block_parent_[coarse_start_] = -1;
  open.push({heuristic(coarse_start_), 0.0f, coarse_start_});
  const float diag = std::sqrt(2.0f);
  bool reached = false;
  int visited = 0;
  while (!open.empty()) {
    const Entry top = open.pop();
    const int b = top.cell;
    if (block_done_[b] == 2 || top.depth > block_g_[b]) continue;
    block_done_[b] = 2;
    ++visited;
    if (b == coarse_goal_) {
      reached = true;
      break;
    }
    const int bx = b % bw_, by = b / bw_;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = bx + dx, ny = by + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= bw_ || ny >= bh_) continue;
        const int k = ny * bw_ + nx;
        const float ck = blockCost(nx, ny);  // also stamps k for this generation
        if (!std::isfinite(ck) || block_done_[k] == 2 || !crossable(bx, by, dx, dy)) continue;
        const float g = top.depth + ck * kBlock * (dx != 0 && dy != 0 ? diag : 1.0f);
        if (block_done_[k] == 0 || g < block_g_[k]) {
          block_done_[k] = 1;
          block_g_[k] = g;
          block_parent_[k] = b;
          open.push({g + heuristic(k), g, k});
        }
      }
    }
  }
  plan.coarse_blocks = visited;
  if (!reached) return false;
  coarse_path_.clear();
  for (int b = coarse_goal_; b >= 0; b = block_parent_[b]) coarse_path_.push_back(b);
  return true;
}

bool GlobalPlanner::crossable(int bx, int by, int dx, int dy) const {
  const int w = width_;
  auto passable = [&](int x, int y) {
    const int i = y * w + x;
    return std::isfinite(cellCost(i));
  };
  const int x0 = bx * kBlock, y0 = by * kBlock;
  if (dx != 0 && dy != 0) {
    // Only the corner cells touch: one diagonal step that must not cut a corner.
    const int ax = dx > 0 ? x0 + kBlock - 1 : x0, ay = dy > 0 ? y0 + kBlock - 1 : y0;
    const int cx = ax + dx, cy = ay + dy;
    if (cx < 0 || cy < 0 || cx >= w || cy >= height_ || ax >= w || ay >= height_) return false;
    return passable(ax, ay) && passable(cx, cy) && passable(cx, ay) && passable(ax, cy);
  }
  // Straight: some pair of facing boundary cells, both traversable.
  for (int t = 0; t < kBlock; ++t) {
    int ax, ay;
    if (dx != 0) {
      ax = dx > 0 ? x0 + kBlock - 1 : x0;
      ay = y0 + t;
    } else {
      ax = x0 + t;
      ay = dy > 0 ? y0 + kBlock - 1 : y0;
    }
    const int cx = ax + dx, cy = ay + dy;
    if (ax >= w || ay >= height_ || cx < 0 || cy < 0 || cx >= w || cy >= height_) continue;
    if (passable(ax, ay) && passable(cx, cy)) return true;
  }
  return false;
}

void GlobalPlanner::markCorridor(int radius) {
  if (++corridor_gen_ == 0) {
    std::fill(corridor_.begin(), corridor_.end(), 0);
    corridor_gen_ = 1;
  }
  for (int b : coarse_path_) {
    const int bx = b % bw_, by = b / bw_;
    for (int y = std::max(0, by - radius); y <= std::min(bh_ - 1, by + radius); ++y) {
      for (int x = std::max(0, bx - radius); x <= std::min(bw_ - 1, bx + radius); ++x) corridor_[y * bw_ + x] = corridor_gen_;
    }
  }
}

void GlobalPlanner::nextGeneration() {
  if (++generation_ == 0) {  // wrapped around: clear once every 2^32 searches
    std::fill(stamp_.begin(), stamp_.end(), 0);
    std::fill(block_stamp_.begin(), block_stamp_.end(), 0);
    generation_ = 1;
  }
}

template <class Queue>
bool GlobalPlanner::search(const Costmap& map, int start, int goal, Plan& plan) {
  const int w = map.width(), h = map.height();
  // done_ is valid where stamp_ is current; a cell is done once popped.
  auto isDone = [&](int i) { return stamp_[i] == generation_ && done_[i]; };
  // The wavefront from the goal, ordered by potential plus a lower bound of what remains to the
  // start (A*-ordered, as global_planner's A* with its quadratic potential): it stops at the start
  // having touched the cells near the way, not the whole map.
  const int sx = start % w, sy = start / w;
  const float neutral = static_cast<float>(params_.neutral_cost);
  auto bound = [&](int i) {
    if (!params_.use_bounds) return 0.0f;
    return kPotentialBoundScale * neutral * octile(std::abs(i % w - sx), std::abs(i / w - sy));
  };
  Queue open(1.0f, 2.0f * std::sqrt(2.0f) * cost::kInscribed);
  setValue(goal, 0.0f);
  done_[goal] = 0;
  open.push({bound(goal), 0.0f, goal});
  bool reached = false;
  while (!open.empty()) {
    const Entry top = open.pop();
    const int i = top.cell;
    if (isDone(i) || top.depth > value(i)) continue;
    done_[i] = 1;
    ++plan.expanded;
    if (i == start) {
      reached = true;
      break;
    }
    const int x = i % w, y = i / w;
    const int nb[4] = {x > 0 ? i - 1 : -1, x < w - 1 ? i + 1 : -1, y > 0 ? i - w : -1, y < h - 1 ? i + w : -1};
    for (int k : nb) {
      if (k < 0 || isDone(k) || !allowed(k % w, k / w)) continue;
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
        open.push({pot + bound(k), pot, k});
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

template <class Queue>
bool GlobalPlanner::searchAStar(const Costmap& map, int start, int goal, Plan& plan) {
  const int w = map.width(), h = map.height();
  const float neutral = static_cast<float>(params_.neutral_cost);
  const int gx = goal % w, gy = goal / w;
  // The octile distance: exact on a free 8-connected grid, consistent (no cell costs less than
  // neutral_cost).
  auto heuristic = [&](int i) {
    const int ax = std::abs(i % w - gx), ay = std::abs(i / w - gy);
    return params_.use_bounds ? neutral * octile(ax, ay) : neutral * std::hypot(float(ax), float(ay));
  };
  auto isDone = [&](int i) { return stamp_[i] == generation_ && done_[i]; };
  Queue open(1.0f, 2.0f * std::sqrt(2.0f) * cost::kInscribed);
  setValue(start, 0.0f);
  done_[start] = 0;
  parent_[start] = -1;
  open.push({heuristic(start), 0.0f, start});
  const float diag = std::sqrt(2.0f);
  bool reached = false;
  while (!open.empty()) {
    const int i = open.pop().cell;
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
        if (isDone(k) || !allowed(x + dx, y + dy)) continue;
        const float ck = cellCost(k);
        if (!std::isfinite(ck)) continue;
        if (cutsCorner(i, dx, dy, w)) continue;
        const float g = value(i) + ck * (dx != 0 && dy != 0 ? diag : 1.0f);
        if (g < value(k)) {
          if (stamp_[k] != generation_) done_[k] = 0;
          setValue(k, g);
          parent_[k] = i;
          open.push({g + heuristic(k), g, k});
        }
      }
    }
  }
  if (!reached) return false;
  for (int i = goal; i >= 0; i = parent_[i]) plan.path.push_back(map.cellCenter({i % w, i / w}));
  std::reverse(plan.path.begin(), plan.path.end());
  return true;
}

namespace {
double pathLength(const std::vector<Eigen::Vector2d>& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}
}  // namespace

Plan planPreferringRoom(GlobalPlanner& planner, const Costmap& map, const Eigen::Vector2d& start,
                        const Eigen::Vector2d& goal, int roomy_cost, int lethal_cost, double max_detour_m,
                        int* used_cost) {
  int used = roomy_cost;
  planner.setLethalCost(roomy_cost);
  Plan roomy = planner.makePlan(map, start, goal);
  if (roomy_cost < lethal_cost &&
      (roomy.status == PlanStatus::kNoPath ||
       (roomy.status == PlanStatus::kOk && pathLength(roomy.path) - (goal - start).norm() > max_detour_m))) {
    planner.setLethalCost(lethal_cost);
    Plan tight = planner.makePlan(map, start, goal);
    const bool keep_roomy = roomy.status == PlanStatus::kOk &&
                            (tight.status != PlanStatus::kOk || pathLength(roomy.path) <= pathLength(tight.path) + max_detour_m);
    if (!keep_roomy) {
      roomy = std::move(tight);
      used = lethal_cost;
    }
  }
  if (used_cost) *used_cost = used;
  return roomy;
}

}  // namespace core
}  // namespace mbot
