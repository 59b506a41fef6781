// Global planning on a costmap, as navfn does it and with an A* option.
//
// Every traversable cell costs neutral_cost + cost_factor * its costmap value (navfn: 50 + 0.8 c);
// cells at lethal_cost or above (global_planner's parameter; 253, inscribed, by default) are
// obstacles, 255 (unknown) costs 253 when allow_unknown and is an obstacle otherwise. move_base sets
// lethal_cost to the costmap's contactCost: a centre nearer a lethal cell than that is one where the
// local planner's footprint already covers the lethal cell, so a plan through it cannot be followed.
// - Dijkstra (use_astar false): navfn's wavefront from the goal with its quadratic potential update
//   (the potential at a cell interpolates between its two smallest 4-neighbours, approximating the
//   continuous distance field), stopped once the start is reached; the path descends the potential
//   from the start, to the neighbour (8-connected) of lowest potential.
// - A* (use_astar true): 8-connected search from the start with the octile distance times
//   neutral_cost as heuristic (consistent: no cell costs less; the euclidean one with use_bounds
//   false).
// With use_bounds (the default), a plan is hierarchical: an A* over blocks of kBlock x kBlock cells
// (a block costs the mean of its traversable cells; blocks with none are obstacles; neighbours are
// connected where a fine step crosses their common edge, so any wall at least kBlock - 1 cells
// thick is seen)
// finds the way through the rooms and doors, then the fine search runs only in the corridor of
// blocks within kCorridorRadius blocks of that way, ordered by a lower bound of what remains (the
// octile distance). Should the corridor hold no path (a wall thinner than a block, that the coarse
// level does not see), it is widened four times, then the whole map is searched: a path is found
// whenever one exists. No coarse path proves there is no path, without flooding the map.
// Failures are typed (Nav2's StartOccupied, GoalOccupied, NoValidPathCouldBeFound...), never an
// empty path without a reason.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/costmap.h"

namespace mbot {
namespace core {

enum class PlanStatus { kOk, kStartOffMap, kGoalOffMap, kStartOccupied, kGoalOccupied, kNoPath };
const char* toString(PlanStatus status);

struct PlannerParams {
  bool use_astar = false;
  bool allow_unknown = true;       ///< navfn `allow_unknown`
  double default_tolerance = 0.0;  ///< [m] a blocked goal moves to the nearest free cell this close
  double neutral_cost = 50.0;
  double cost_factor = 0.8;
  /// Cells at this cost or above are obstacles (global_planner's `lethal_cost`, 1..253).
  int lethal_cost = cost::kInscribed;
  /// false: the searches of before (the whole wavefront / euclidean A*, a binary heap, no coarse
  /// level), a reference for benchmarks and tests; the paths are the same up to ties.
  bool use_bounds = true;
};

struct Plan {
  PlanStatus status = PlanStatus::kNoPath;
  std::vector<Eigen::Vector2d> path;  ///< cell centres [m] from start to goal, costmap frame
  Eigen::Vector2d goal = Eigen::Vector2d::Zero();  ///< the goal actually used (after tolerance)
  std::string message;                ///< why, for a failure
  int expanded = 0;                   ///< cells the search finalized
  int coarse_blocks = 0;              ///< blocks the coarse search visited
};

class GlobalPlanner;

/// [m] How much longer a roomy way may be than the tightest one and still be taken. Through a gap
/// the footprint clears by a centimetre or two the robot drives at a third of its speed or less
/// (the local planner's latency margin) for about a metre; 2 m at full speed is that time. A
/// longer detour, without a map mostly through space not seen yet, costs more than the gap.
constexpr double kMaxRoomyDetour_m = 2.0;

/// A plan that keeps room to spare where that costs little. Plans with `roomy_cost` as lethal
/// first; plans again with `lethal_cost` when that finds no way, or when its way may be more than
/// `max_detour_m` longer than the tighter one's (the second search runs only when the roomy way
/// exceeds the straight line by more than `max_detour_m`), and then takes the tighter way unless
/// the roomy one is within `max_detour_m` of it. `used_cost` (optional): the lethal cost of the
/// returned plan (for a failure, of the last search). The planner's lethal cost is left at
/// `lethal_cost`'s after a second search, at `roomy_cost` otherwise.
Plan planPreferringRoom(GlobalPlanner& planner, const Costmap& map, const Eigen::Vector2d& start,
                        const Eigen::Vector2d& goal, int roomy_cost, int lethal_cost,
                        double max_detour_m = kMaxRoomyDetour_m, int* used_cost = nullptr);

class GlobalPlanner {
 public:
  explicit GlobalPlanner(const PlannerParams& params = PlannerParams());
  const PlannerParams& params() const { return params_; }
  /// Another lethal_cost (1..253) for the next plans.
  void setLethalCost(int lethal_cost);
  /// Plans on `map` (start and goal in its frame, m). Work is proportional to the cells the search
  /// touches, not to the map: buffers persist between calls and are invalidated by a generation
  /// stamp instead of being cleared (navfn copies and clears the whole costmap on every call).
  Plan makePlan(const Costmap& map, const Eigen::Vector2d& start, const Eigen::Vector2d& goal);
  /// The last search's value at cell index i (Dijkstra: potential; A*: cost from the start); +inf
  /// where the search did not reach.
  float valueAt(std::size_t i) const { return stamp_[i] == generation_ ? value_[i] : kUnreached; }

 private:
  static constexpr float kUnreached = std::numeric_limits<float>::infinity();
  float cellCost(int i) const {
    if (i == start_) return start_cost_;
    const uint8_t c = (*costs_)[i];
    const float v = cost_of_value_[c];
    // A robot whose centre stands in a blocked cell (at lethal_cost or above, not lethal) may leave
    // through the blocked cells around it.
    if (escape_cells_ > 0 && c >= params_.lethal_cost && c <= cost::kInscribed && v == kUnreached) {
      const int dx = i % map_width_ - start_x_, dy = i / map_width_ - start_y_;
      if (dx * dx + dy * dy <= escape_cells_ * escape_cells_) return escape_cost_;
    }
    return v;
  }
  /// A diagonal step (dx, dy both non-zero) from cell i must not cut the corner of an obstacle.
  bool cutsCorner(int i, int dx, int dy, int w) const {
    return dx != 0 && dy != 0 && (!std::isfinite(cellCost(i + dx)) || !std::isfinite(cellCost(i + dy * w)));
  }
  float value(int i) const { return valueAt(static_cast<std::size_t>(i)); }
  void setValue(int i, float v) {
    stamp_[i] = generation_;
    value_[i] = v;
  }
  template <class Queue>
  bool search(const Costmap& map, int start, int goal, Plan& plan);
  template <class Queue>
  bool searchAStar(const Costmap& map, int start, int goal, Plan& plan);
  /// A* over the blocks from start's to goal's; fills coarse_path_. False: no path exists.
  bool coarsePlan(int start, int goal, Plan& plan);
  /// The mean cost of block (bx, by)'s traversable cells, +inf when it has none (cached per search).
  float blockCost(int bx, int by);
  /// Whether one fine step leads from block (bx, by) into its neighbour (bx + dx, by + dy): a pair
  /// of facing boundary cells both traversable (for a diagonal neighbour, the corner step).
  bool crossable(int bx, int by, int dx, int dy) const;
  void markCorridor(int radius);
  bool allowed(int x, int y) const {
    return !corridor_active_ || corridor_[(y / kBlock) * bw_ + x / kBlock] == corridor_gen_;
  }
  void nextGeneration();

 public:
  static constexpr int kBlock = 4;            ///< [cells] side of a coarse block
  /// [m] A start in a blocked cell (a robot the costmap puts against a wall end or a person who
  /// walked up to it) may leave through blocked cells this close to it; navfn clears only the
  /// robot's own cell and then finds no way out of such a pocket.
  static constexpr double kStartEscape_m = 0.3;
  static constexpr int kCorridorRadius = 3;   ///< [blocks] around the coarse way

 private:
  PlannerParams params_;
  float cost_of_value_[256];
  float start_cost_ = 0.0f;
  int start_ = -1;
  // The start's blocked surroundings (kStartEscape_m), passable only when the start is blocked.
  int escape_cells_ = 0, start_x_ = 0, start_y_ = 0, map_width_ = 1;
  float escape_cost_ = 0.0f;
  const std::vector<uint8_t>* costs_ = nullptr;
  std::vector<float> value_;
  std::vector<uint32_t> stamp_;   // == generation_: value_ and the done flag are from this search
  std::vector<uint8_t> done_;
  std::vector<int> parent_;
  uint32_t generation_ = 0;
  // Coarse level (per block; valid where block_stamp_ == generation_).
  int width_ = 0, height_ = 0, bw_ = 0, bh_ = 0;
  std::vector<float> block_cost_, block_g_;
  std::vector<uint32_t> block_stamp_;
  std::vector<int> block_parent_;
  std::vector<uint8_t> block_done_;
  std::vector<int> coarse_path_;
  int coarse_start_ = -1, coarse_goal_ = -1;
  std::vector<uint32_t> corridor_;  // == corridor_gen_: the block is in the corridor
  uint32_t corridor_gen_ = 0;
  bool corridor_active_ = false;
};

}  // namespace core
}  // namespace mbot
