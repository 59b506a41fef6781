#include "mbot_slam_navigation/core/local_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "mbot_slam_navigation/core/bresenham.h"
#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {
namespace {

constexpr double kSpinSpot_m = 0.05;  // moving less than this counts as turning on the spot
// [rad] The plan a heading_lookahead ahead lies farther than this off the robot's heading: it turns
// on the spot first. Only slow forward arcs stay near such a plan, and they end in nearly the same
// cells (0.05 m in sim_time): their costs tie, the straight one wins, and the robot crept on at
// min_vel_x while the plan turned away (in the home, about 5 s more over 75-90 m of goals, measured).
constexpr double kFacingAway_rad = M_PI / 3.0;
// [m] Turning on the spot aims at the plan this far ahead of the robot's nearest plan point: far
// enough that the cells' 45-degree steps average out, near enough to be the way out of where it
// stands.
constexpr double kTurnLookahead_m = 0.5;
// [m] The local goal (what the goal distances lead to) lies at most this far along the plan ahead
// of the robot (Nav2's DWB prunes its plan so, forward_prune_distance 2.0 m). ROS takes the plan's
// last point in the local costmap, up to 3.5 m away: the goal distances count cells, not the
// global planner's costs, and around a cluster of obstacles a shorter way to that point through
// a corridor the plan avoided made every move along the plan a move away; the robot crept on at
// min_vel_x for 10-20 s, until move_base declared an oscillation.
constexpr double kLocalGoalAhead_m = 2.0;
// [rad] Within this of the plan kTurnLookahead_m ahead the robot faces its way.
constexpr double kFacingPlan_rad = 0.35;

bool isObstacleValue(uint8_t v) { return v == cost::kLethal || v == cost::kInscribed || v == cost::kNoInformation; }

/// ROS's computeNewVelocity: move towards the sampled speed by at most a * dt.
double approach(double target, double current, double acc, double dt) {
  return target >= current ? std::min(target, current + acc * dt) : std::max(target, current - acc * dt);
}

}  // namespace

void LocalPlannerParams::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0)) throw std::invalid_argument(std::string(name) + " must be positive, got " + std::to_string(v));
  };
  positive(sim_time, "sim_time");
  positive(sim_granularity, "sim_granularity");
  positive(angular_sim_granularity, "angular_sim_granularity");
  positive(sim_period, "sim_period (1 / controller_frequency)");
  if (acc_lim_x < 0 || acc_lim_y < 0 || acc_lim_theta < 0) throw std::invalid_argument("acc_lim_x/y/theta must be >= 0");
  if (min_vel_x > max_vel_x) throw std::invalid_argument("min_vel_x must not exceed max_vel_x");
  if (min_vel_theta > max_vel_theta) throw std::invalid_argument("min_vel_theta must not exceed max_vel_theta");
  if (vx_samples < 1 || vtheta_samples < 1) throw std::invalid_argument("vx_samples and vtheta_samples must be >= 1");
}

// --- DistanceGrid (MapGrid) ----------------------------------------------------------------------

void DistanceGrid::reset(const Costmap& map) {
  width_ = map.width();
  const std::size_t n = map.costs().size();
  dist_.assign(n, static_cast<float>(n + 1));
  within_robot_.assign(n, 0);
  target_.assign(n, 0);
}

void DistanceGrid::markWithinRobot(const std::vector<Cell>& cells) {
  for (const Cell& c : cells) within_robot_[static_cast<std::size_t>(c.y) * width_ + c.x] = 1;
}

bool DistanceGrid::setPath(const Costmap& map, const std::vector<Eigen::Vector2d>& plan) {
  std::vector<int> queue;
  bool started = false;
  for (const Eigen::Vector2d& p : densifyPlan(plan, map.resolution())) {
    const Cell c = map.worldToCell(p);
    if (map.contains(c) && map.cost(c) != cost::kNoInformation) {
      const int i = static_cast<int>(map.index(c));
      if (!target_[i]) {
        target_[i] = 1;
        dist_[i] = 0.0f;
        queue.push_back(i);
      }
      started = true;
    } else if (started) {
      break;
    }
  }
  if (!started) return false;
  propagate(map, queue);
  return true;
}

bool DistanceGrid::setLocalGoal(const Costmap& map, const std::vector<Eigen::Vector2d>& plan, Eigen::Vector2d* local_goal) {
  int goal = -1;
  bool started = false;
  for (const Eigen::Vector2d& p : densifyPlan(plan, map.resolution())) {
    const Cell c = map.worldToCell(p);
    if (map.contains(c) && map.cost(c) != cost::kNoInformation) {
      goal = static_cast<int>(map.index(c));
      if (local_goal) *local_goal = p;
      started = true;
    } else if (started) {
      break;
    }
  }
  if (goal < 0) return false;
  target_[goal] = 1;
  dist_[goal] = 0.0f;
  std::vector<int> queue{goal};
  propagate(map, queue);
  return true;
}

void DistanceGrid::setSources(const Costmap& map, const std::vector<Cell>& cells) {
  std::vector<int> queue;
  for (const Cell& c : cells) {
    if (!map.contains(c)) continue;
    const int i = static_cast<int>(map.index(c));
    if (target_[i]) continue;
    target_[i] = 1;
    dist_[i] = 0.0f;
    queue.push_back(i);
  }
  propagate(map, queue);
}

void DistanceGrid::propagate(const Costmap& map, std::vector<int>& queue) {
  // Breadth first from all targets at once: every step costs 1, so FIFO order is distance order.
  const int w = map.width(), h = map.height();
  const std::vector<uint8_t>& costs = map.costs();
  const float obstacle_cost = static_cast<float>(dist_.size());
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int i = queue[head];
    const int x = i % w, y = i / w;
    const int nb[4] = {x > 0 ? i - 1 : -1, x < w - 1 ? i + 1 : -1, y > 0 ? i - w : -1, y < h - 1 ? i + w : -1};
    for (int k : nb) {
      if (k < 0 || target_[k]) continue;
      if (!within_robot_[k] && isObstacleValue(costs[k])) {
        dist_[k] = obstacle_cost;
        target_[k] = 1;
        continue;
      }
      const float d = dist_[i] + 1.0f;
      if (d < dist_[k]) dist_[k] = d;
      target_[k] = 1;
      queue.push_back(k);
    }
  }
}

std::vector<Eigen::Vector2d> densifyPlan(const std::vector<Eigen::Vector2d>& plan, double resolution) {
  std::vector<Eigen::Vector2d> out;
  if (plan.empty()) return out;
  out.push_back(plan.front());
  for (std::size_t i = 1; i < plan.size(); ++i) {
    const Eigen::Vector2d a = out.back(), b = plan[i];
    const double d = (b - a).norm();
    const int extra = static_cast<int>(d / resolution);
    for (int k = 1; k <= extra; ++k) out.push_back(a + (b - a) * (k * resolution / d));
    out.push_back(b);
  }
  return out;
}

std::vector<Cell> footprintCells(const Costmap& map, const Eigen::Vector3d& pose, const Footprint& footprint) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  std::vector<Eigen::Vector2d> world;
  for (const auto& v : footprint) world.emplace_back(pose.x() + c * v.x() - s * v.y(), pose.y() + s * v.x() + c * v.y());
  std::vector<Cell> cells;
  std::vector<uint8_t> seen;
  Cell lo{map.width(), map.height()}, hi{-1, -1};
  for (const auto& p : world) {
    const Cell cell = map.worldToCell(p);
    lo = {std::min(lo.x, cell.x), std::min(lo.y, cell.y)};
    hi = {std::max(hi.x, cell.x), std::max(hi.y, cell.y)};
  }
  lo = {std::max(lo.x, 0), std::max(lo.y, 0)};
  hi = {std::min(hi.x, map.width() - 1), std::min(hi.y, map.height() - 1)};
  if (hi.x < lo.x || hi.y < lo.y) return cells;
  const int bw = hi.x - lo.x + 1;
  seen.assign(static_cast<std::size_t>(bw) * (hi.y - lo.y + 1), 0);
  auto add = [&](const Cell& cell) {
    if (cell.x < lo.x || cell.y < lo.y || cell.x > hi.x || cell.y > hi.y) return;
    uint8_t& f = seen[static_cast<std::size_t>(cell.y - lo.y) * bw + (cell.x - lo.x)];
    if (!f) {
      f = 1;
      cells.push_back(cell);
    }
  };
  for (std::size_t i = 0, j = world.size() - 1; i < world.size(); j = i++) {
    walkLine(map.worldToCell(world[j]), map.worldToCell(world[i]), [&](const Cell& cell) {
      add(cell);
      return true;
    });
  }
  // Interior: cell centres inside the polygon (even-odd rule).
  for (int y = lo.y; y <= hi.y; ++y) {
    for (int x = lo.x; x <= hi.x; ++x) {
      if (insidePolygon(world.data(), world.size(), map.cellCenter({x, y}))) add({x, y});
    }
  }
  return cells;
}

// --- LocalPlanner --------------------------------------------------------------------------------

LocalPlanner::LocalPlanner(const LocalPlannerParams& params, const Footprint& footprint)
    : params_(params),
      footprint_(footprint),
      path_bias_(params.path_distance_bias),
      goal_bias_(params.goal_distance_bias),
      occ_scale_(params.occdist_scale) {
  params_.validate();
  validateFootprint(footprint_);
  circumscribed_ = circumscribedRadius(footprint_);
}

void LocalPlanner::buildNonZeroTable(const Costmap& map) {
  table_w_ = map.width();
  table_h_ = map.height();
  nonzero_.assign(static_cast<std::size_t>(table_w_ + 1) * (table_h_ + 1), 0);
  blocking_.assign(nonzero_.size(), 0);
  const uint8_t* c = map.costs().data();
  for (int y = 0; y < table_h_; ++y) {
    int row = 0, row_blocking = 0;
    const std::size_t above = static_cast<std::size_t>(y) * (table_w_ + 1), here = above + table_w_ + 1;
    for (int x = 0; x < table_w_; ++x) {
      const uint8_t v = c[static_cast<std::size_t>(y) * table_w_ + x];
      row += v != cost::kFree;
      row_blocking += v >= cost::kLethal;  // lethal or unknown: what makes a footprint invalid
      nonzero_[here + x + 1] = nonzero_[above + x + 1] + row;
      blocking_[here + x + 1] = blocking_[above + x + 1] + row_blocking;
    }
  }
}

int LocalPlanner::footprintCostAt(const Costmap& map, const Eigen::Vector3d& pose, bool* defer, double box_margin) const {
  if (table_valid_) {
    // Every outline cell lies in the cells of the circumscribed circle's bounding square.
    const Cell lo = map.worldToCell({pose.x() - circumscribed_, pose.y() - circumscribed_});
    const Cell hi = map.worldToCell({pose.x() + circumscribed_, pose.y() + circumscribed_});
    if (lo.x >= 0 && lo.y >= 0 && hi.x < table_w_ && hi.y < table_h_) {
      const int stride = table_w_ + 1;
      auto count = [&](const std::vector<int>& table) {
        const int* t = table.data();
        return t[(hi.y + 1) * stride + hi.x + 1] - t[lo.y * stride + hi.x + 1] - t[(hi.y + 1) * stride + lo.x] + t[lo.y * stride + lo.x];
      };
      if (count(nonzero_) == 0) return 0;
      if (defer && count(blocking_) == 0) {
        *defer = true;
        // A lower bound of the outline's cost: the costs at four of its corners (outline cells),
        // which near a wall are usually its highest.
        const double c = std::cos(pose.z()), s = std::sin(pose.z());
        const std::size_t n = footprint_.size(), step = std::max<std::size_t>(1, n / 4);
        int bound = 0;
        for (std::size_t i = 0; i < n; i += step) {
          const Eigen::Vector2d& v = footprint_[i];
          bound = std::max<int>(bound, map.cost(map.worldToCell({pose.x() + c * v.x() - s * v.y(), pose.y() + s * v.x() + c * v.y()})));
        }
        return bound;
      }
    }
  }
  return footprintCost(map, pose, footprint_, /*unknown_is_obstacle=*/true, box_margin);
}

void LocalPlanner::setPlan(const std::vector<Eigen::Vector2d>& plan) {
  plan_ = plan;
  goal_valid_ = !plan_.empty();
  if (goal_valid_) final_goal_ = plan_.back();
}

void LocalPlanner::resetOscillation() {
  stuck_left_ = stuck_right_ = stuck_left_strafe_ = stuck_right_strafe_ = false;
  rotating_left_ = rotating_right_ = strafe_left_ = strafe_right_ = false;
  escaping_ = false;
  spun_ = 0.0;
}

void LocalPlanner::updateGrids(const Costmap& map, const Eigen::Vector3d& pose) {
  path_bias_ = params_.path_distance_bias * (params_.meter_scoring ? map.resolution() : 1.0);
  goal_bias_ = params_.goal_distance_bias * (params_.meter_scoring ? map.resolution() : 1.0);
  // ROS scales the occupancy weight too (TrajectoryPlanner::reconfigure, which the
  // dynamic_reconfigure server calls at start-up); left unscaled, with meter_scoring it outweighs the
  // distance terms twentyfold at 0.05 m cells and the robot crawled at min_vel_x near every wall.
  occ_scale_ = params_.occdist_scale * (params_.meter_scoring ? map.resolution() : 1.0);
  path_grid_.reset(map);
  goal_grid_.reset(map);
  const std::vector<Cell> robot = footprintCells(map, pose, footprint_);
  path_grid_.markWithinRobot(robot);
  goal_grid_.markWithinRobot(robot);  // ROS marks only the path map; the goal map needs it as much
  path_grid_.setPath(map, plan_);
  dense_plan_.clear();
  dense_reach_ = 2.0 * map.resolution();
  for (const Eigen::Vector2d& p : densifyPlan(plan_, map.resolution())) {
    if (!map.contains(map.worldToCell(p))) {
      if (!dense_plan_.empty()) break;
      continue;
    }
    dense_plan_.push_back(p);
  }
  // The local goal: the last plan point in the map that the robot can reach through the local
  // costmap. ROS takes the last one in the map whatever stands between: where the local costmap
  // sees an obstacle the global one does not yet (its inflation at the map's edge, a gap that has
  // just closed), no cell around the robot had a goal distance, every trajectory was invalid, and
  // move_base planned the same plan again every cycle with the robot stopped. A robot that can
  // reach no plan point beyond its own cells (boxed in) keeps ROS's local goal, and no command.
  reach_grid_.reset(map);
  reach_grid_.markWithinRobot(robot);
  reach_grid_.setSources(map, robot);
  // No farther than kLocalGoalAhead_m along the plan from its point nearest the robot.
  std::size_t ahead = dense_plan_.size();
  const int nearest = nearestPlanIndex(pose.head<2>(), std::numeric_limits<double>::infinity());
  if (nearest >= 0) {
    double along = 0.0;
    for (ahead = static_cast<std::size_t>(nearest) + 1; ahead < dense_plan_.size(); ++ahead) {
      along += (dense_plan_[ahead] - dense_plan_[ahead - 1]).norm();
      if (along > kLocalGoalAhead_m) break;
    }
  }
  std::size_t reachable = dense_plan_.size();
  for (std::size_t i = ahead; i-- > 0;) {
    if (reach_grid_.at(map.worldToCell(dense_plan_[i])) < reach_grid_.obstacle()) {
      reachable = i;
      break;
    }
  }
  // Only the robot's own cells reached, and the plan goes on: boxed in.
  if (reachable + 1 < dense_plan_.size() && reach_grid_.at(map.worldToCell(dense_plan_[reachable])) < 1.0) {
    reachable = dense_plan_.size();
  }
  if (reachable < dense_plan_.size()) {
    goal_grid_.setLocalGoal(map, std::vector<Eigen::Vector2d>(dense_plan_.begin(), dense_plan_.begin() + reachable + 1), &local_goal_);
  } else {
    goal_grid_.setLocalGoal(map, plan_, &local_goal_);
  }
}

int LocalPlanner::nearestPlanIndex(const Eigen::Vector2d& point, double within) const {
  int best = -1;
  double best_d2 = within * within;
  for (std::size_t i = 0; i < dense_plan_.size(); ++i) {
    const double d2 = (dense_plan_[i] - point).squaredNorm();
    if (d2 <= best_d2) {
      best_d2 = d2;
      best = static_cast<int>(i);
    }
  }
  return best;
}

bool LocalPlanner::planAhead(const Eigen::Vector2d& point, double lookahead, Eigen::Vector2d* ahead) const {
  const int nearest = nearestPlanIndex(point, std::numeric_limits<double>::infinity());
  if (nearest < 0) return false;
  double along = 0.0;
  std::size_t i = static_cast<std::size_t>(nearest);
  while (i + 1 < dense_plan_.size() && along < lookahead) {
    along += (dense_plan_[i + 1] - dense_plan_[i]).norm();
    ++i;
  }
  *ahead = dense_plan_[i];
  return true;
}

int LocalPlanner::alongPlan(const Eigen::Vector2d& point) const { return nearestPlanIndex(point, dense_reach_); }

double LocalPlanner::headingDiff(const Costmap& map, const Cell& cell, const Eigen::Vector3d& pose) const {
  // The farthest plan point in line of sight (no lethal/inscribed/unknown cell in between).
  for (int i = static_cast<int>(plan_.size()) - 1; i >= 0; --i) {
    const Cell g = map.worldToCell(plan_[i]);
    if (!map.contains(g)) continue;
    const bool clear = walkLine(cell, g, [&](const Cell& c) { return !isObstacleValue(map.cost(c)); });
    if (clear) {
      const Eigen::Vector2d gc = map.cellCenter(g);
      return std::abs(normalizeAngle(std::atan2(gc.y() - pose.y(), gc.x() - pose.x()) - pose.z()));
    }
  }
  return std::numeric_limits<double>::max();
}

void LocalPlanner::generate(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel, double vx_samp,
                            double vy_samp, double vth_samp, double impossible_cost, Trajectory& traj, double exact_below) const {
  const LocalPlannerParams& p = params_;
  const double vmag = std::hypot(vx_samp, vy_samp);
  int steps = p.heading_scoring ? static_cast<int>(p.sim_time / p.sim_granularity + 0.5)
                                : static_cast<int>(std::max(vmag * p.sim_time / p.sim_granularity,
                                                            std::abs(vth_samp) / p.angular_sim_granularity) + 0.5);
  steps = std::max(steps, 1);
  const double dt = p.sim_time / steps;
  traj.xv = vx_samp;
  traj.yv = vy_samp;
  traj.thetav = vth_samp;
  traj.cost = -1.0;
  traj.cost_exact = true;
  traj.points.clear();
  double x = pose.x(), y = pose.y(), th = pose.z();
  double vx = vel.x(), vy = vel.y(), vth = vel.z();
  double path_dist = 0.0, goal_dist = 0.0, occ = 0.0, heading = 0.0, time = 0.0;
  // Steps whose footprint is known valid but whose outline cost was not computed (see exact_below).
  bool deferred = false;
  const bool may_defer = table_valid_ && exact_below < std::numeric_limits<double>::infinity();
  const double box_margin = map.hasBoxes() ? box_latency_ * (vmag + std::abs(vth_samp) * circumscribed_) : 0.0;
  for (int i = 0; i < steps; ++i) {
    const Cell cell = map.worldToCell({x, y});
    if (!map.contains(cell)) return;  // off the local map
    if (map.cost(cell) > max_centre_cost_) return;  // deeper into what the footprint touches (escaping)
    if (i > 0 && min_lethal_distance_ < std::numeric_limits<double>::infinity() &&
        nearestLethal(map, {x, y}, min_lethal_distance_) < min_lethal_distance_ - 1e-3)
      return;  // nearer to what stands inside the footprint (escaping)
    const int fp = footprintCostAt(map, {x, y, th}, may_defer ? &deferred : nullptr, box_margin);
    if (fp < 0) return;
    occ = std::max({occ, static_cast<double>(fp), static_cast<double>(map.cost(cell))});
    if (p.simple_attractor) {
      goal_dist = (Eigen::Vector2d(x, y) - final_goal_).squaredNorm();
    } else {
      bool update = true;
      if (p.heading_scoring) {
        if (time >= p.heading_scoring_timestep && time < p.heading_scoring_timestep + dt) heading = headingDiff(map, cell, {x, y, th});
        else update = false;
      }
      if (update) {
        path_dist = path_grid_.at(cell);
        goal_dist = goal_grid_.at(cell);
        if (impossible_cost <= goal_dist || impossible_cost <= path_dist) {
          traj.cost = -2.0;
          return;
        }
      }
    }
    traj.points.emplace_back(x, y, th);
    vx = approach(vx_samp, vx, p.acc_lim_x, dt);
    vy = approach(vy_samp, vy, p.acc_lim_y, dt);
    vth = approach(vth_samp, vth, p.acc_lim_theta, dt);
    x += (vx * std::cos(th) - vy * std::sin(th)) * dt;
    y += (vx * std::sin(th) + vy * std::cos(th)) * dt;
    th += vth * dt;
    time += dt;
  }
  traj.progress = path_bias_ * path_dist + goal_bias_ * goal_dist;
  const double rest = traj.progress + (p.heading_scoring ? 0.3 * heading : 0.0);
  traj.cost = rest + occ_scale_ * occ;  // a lower bound while steps are deferred
  traj.cost_exact = !deferred;
  if (deferred && traj.cost <= exact_below) {
    // It may win: the outline costs of every step, exactly.
    for (const Eigen::Vector3d& q : traj.points) occ = std::max(occ, static_cast<double>(footprintCost(map, q, footprint_, true, box_margin)));
    traj.cost = rest + occ_scale_ * occ;
    traj.cost_exact = true;
  }
}

double LocalPlanner::scoreTrajectory(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity,
                                     const Eigen::Vector3d& command) {
  if (path_grid_.values().size() != map.costs().size()) updateGrids(map, pose);
  const double scale = footprint_scale_;  // lastFootprintScale() stays findBestPath's
  const Footprint full = useEscapeFootprint(map, pose);
  Trajectory t;
  generate(map, pose, velocity, command.x(), command.y(), command.z(), path_grid_.obstacle(), t);
  restoreFootprint(full);
  footprint_scale_ = scale;
  return t.cost;
}

Footprint LocalPlanner::useEscapeFootprint(const Costmap& map, const Eigen::Vector3d& pose) {
  // A footprint that already touches a lethal cell where the robot stands (a wall end the costmap's
  // cells round onto its outline, a person who walked up to it, a turn the base drove wider than
  // planned) makes every trajectory invalid, turning away included, and the robot would wait there
  // for ever. It is then planned with the largest shrunken footprint that is free where it stands,
  // and no step may bring its centre nearer to an obstacle than it is (a higher centre cost): moves
  // out and along are allowed, deeper ones are not, and the full footprint returns once it is clear.
  // A lethal cell inside the footprint but off its outline (a person who walked into the robot,
  // seen by the laser from inside or marked at range_min when it covers the laser) leaves the
  // outline free: the footprint stays whole, and only the rule on the distance applies.
  Footprint full = footprint_;
  footprint_scale_ = 1.0;
  full_radius_ = circumscribed_;
  max_centre_cost_ = cost::kNoInformation;
  min_lethal_distance_ = std::numeric_limits<double>::infinity();
  const Cell here = map.worldToCell(pose.head<2>());
  const double inscribed = inscribedRadius(full);
  const double inside = nearestLethal(map, pose.head<2>(), inscribed);
  if (inside < inscribed) {
    min_lethal_distance_ = inside;
    if (map.contains(here)) max_centre_cost_ = map.cost(here);
  }
  if (footprintCost(map, pose, footprint_, true) < 0) {
    // Boxes (cell_box) are where the laser saw the surface, with a centimetre to spare: a footprint
    // that touches one is shrunk by as little as frees it, or its corners swing into the next one.
    std::vector<double> scales(std::begin(kEscapeScales), std::end(kEscapeScales));
    if (map.hasBoxes()) scales.insert(scales.begin(), std::begin(kBoxEscapeScales), std::end(kBoxEscapeScales));
    for (double scale : scales) {
      Footprint shrunk(full.size());
      for (std::size_t i = 0; i < full.size(); ++i) shrunk[i] = scale * full[i];
      if (footprintCost(map, pose, shrunk, true) >= 0) {
        footprint_ = std::move(shrunk);
        circumscribed_ = scale * full_radius_;
        footprint_scale_ = scale;
        if (map.contains(here)) max_centre_cost_ = map.cost(here);
        min_lethal_distance_ = nearestLethal(map, pose.head<2>(), full_radius_);
        break;
      }
    }
  }
  return full;
}

void LocalPlanner::restoreFootprint(const Footprint& full) {
  footprint_ = full;
  circumscribed_ = full_radius_;
  max_centre_cost_ = cost::kNoInformation;
  min_lethal_distance_ = std::numeric_limits<double>::infinity();
}

double LocalPlanner::nearestLethal(const Costmap& map, const Eigen::Vector2d& at, double within) const {
  // The cells of the square around `at`, as squares (so the distance to a straight wall does not
  // change along it): a few dozen at these radii, and only while escaping.
  const double res = map.resolution();
  const int reach = static_cast<int>(std::ceil(within / res)) + 1;
  const Cell c0 = map.worldToCell(at);
  double best = std::numeric_limits<double>::infinity();
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const Cell c{c0.x + dx, c0.y + dy};
      if (!map.contains(c) || map.cost(c) != cost::kLethal) continue;
      // To the cell's square, or to its box (grown by the box margin).
      const double d = std::sqrt(cell_box::squaredDistance(map.obstacleBounds(c, cell_box::kMargin), at.x(), at.y()));
      if (d <= within && d < best) best = d;
    }
  }
  return best;
}

Trajectory LocalPlanner::simulate(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity,
                                  const Eigen::Vector3d& command) const {
  Trajectory t;
  generate(map, pose, velocity, command.x(), command.y(), command.z(), path_grid_.obstacle(), t);
  return t;
}

double LocalPlanner::progressAt(const Costmap& map, const Eigen::Vector3d& pose) const {
  const Cell here = map.worldToCell(pose.head<2>());
  if (!map.contains(here) || path_grid_.values().size() != map.costs().size()) return std::numeric_limits<double>::infinity();
  return path_bias_ * path_grid_.at(here) + goal_bias_ * goal_grid_.at(here);
}

Trajectory LocalPlanner::findBestPath(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity) {
  updateGrids(map, pose);
  if (shortcuts_) buildNonZeroTable(map);
  table_valid_ = shortcuts_;  // only for this call's map: scoreTrajectory may get another one
  const Footprint full = useEscapeFootprint(map, pose);
  inside_distance_ = min_lethal_distance_ < inscribedRadius(full) ? min_lethal_distance_
                                                                   : std::numeric_limits<double>::infinity();
  Trajectory best = createTrajectories(map, pose, velocity);
  if (best.cost < 0 && map.hasBoxes()) {
    // The latency margin is a reason to drive slowly near boxes, not to stand still: where no
    // move keeps it (a robot already a centimetre or two from a box all round), moves are taken
    // without it, as with whole cells.
    box_latency_ = 0.0;
    best = createTrajectories(map, pose, velocity);
    box_latency_ = kBoxLatency;
  }
  restoreFootprint(full);
  table_valid_ = false;
  if (best.cost < 0) best.xv = best.yv = best.thetav = 0.0;
  return best;
}

void LocalPlanner::resetFlagsIfMoved(const Eigen::Vector3d& pose) {
  if ((pose.head<2>() - prev_).norm() > params_.oscillation_reset_dist) {
    rotating_left_ = rotating_right_ = strafe_left_ = strafe_right_ = false;
    stuck_left_ = stuck_right_ = stuck_left_strafe_ = stuck_right_strafe_ = false;
  }
  if ((pose.head<2>() - escape_).norm() > params_.escape_reset_dist ||
      std::abs(normalizeAngle(pose.z() - escape_theta_)) > params_.escape_reset_theta) {
    escaping_ = false;
  }
}

void LocalPlanner::updateOscillationFlags(const Eigen::Vector3d& pose, const Trajectory& best) {
  // Not moving forward: remember which way it turned or strafed; turning the same way twice
  // without moving oscillation_reset_dist marks that side stuck, so it cannot flip back and forth.
  if (!(best.xv > 0)) {
    if (best.thetav < 0) {
      if (rotating_right_) stuck_right_ = true;
      rotating_right_ = true;
    } else if (best.thetav > 0) {
      if (rotating_left_) stuck_left_ = true;
      rotating_left_ = true;
    } else if (best.yv > 0) {
      if (strafe_right_) stuck_right_strafe_ = true;
      strafe_right_ = true;
    } else if (best.yv < 0) {
      if (strafe_left_) stuck_left_strafe_ = true;
      strafe_left_ = true;
    }
    prev_ = pose.head<2>();
  }
  resetFlagsIfMoved(pose);
}

Trajectory LocalPlanner::createTrajectories(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel) {
  const LocalPlannerParams& p = params_;
  double max_vx = std::max(std::min(p.max_vel_x, speed_limit_), p.min_vel_x);
  if (goal_valid_) max_vx = std::min(max_vx, (final_goal_ - pose.head<2>()).norm() / p.sim_time);
  // The reachable window: one control period for DWA, the whole simulation for trajectory rollout.
  const double window = p.dwa ? p.sim_period : p.sim_time;
  max_vx = std::max(std::min(max_vx, vel.x() + p.acc_lim_x * window), p.min_vel_x);
  const double min_vx = std::max(p.min_vel_x, vel.x() - p.acc_lim_x * window);
  const double max_vth = std::min(p.max_vel_theta, vel.z() + p.acc_lim_theta * window);
  const double min_vth = std::max(p.min_vel_theta, vel.z() - p.acc_lim_theta * window);
  const double dvx = p.vx_samples > 1 ? (max_vx - min_vx) / (p.vx_samples - 1) : 0.0;
  const double dvth = p.vtheta_samples > 1 ? (max_vth - min_vth) / (p.vtheta_samples - 1) : 0.0;
  const double impossible = path_grid_.obstacle();

  Trajectory best, comp;
  best.cost = -1.0;
  bool progressing = false;  // some valid forward trajectory ends nearer the plan and goal, or farther along the plan
  bool any_forward = false;  // some forward trajectory is valid
  const double progress_now = progressAt(map, pose);
  const int along_now = alongPlan(pose.head<2>());
  if ((pose.head<2>() - spin_spot_).norm() > kSpinSpot_m) {
    spun_ = 0.0;
    spin_spot_ = pose.head<2>();
  } else {
    spun_ += std::abs(normalizeAngle(pose.z() - spin_yaw_));
  }
  spin_yaw_ = pose.z();
  // Facing away from the plan (and not already a full turn on the spot without progress): turning
  // in place is preferred to any forward move, as long as one is valid.
  bool facing_away = false;
  Eigen::Vector2d ahead;
  if (!escaping_ && spun_ <= 2.0 * M_PI && planAhead(pose.head<2>(), p.heading_lookahead, &ahead) &&
      (ahead - pose.head<2>()).norm() > 2.0 * map.resolution()) {
    const double bearing = std::atan2(ahead.y() - pose.y(), ahead.x() - pose.x());
    facing_away = std::abs(normalizeAngle(bearing - pose.z())) > kFacingAway_rad;
  }
  // Costs at or above this cannot win (the comparisons below are < best and <= best), so only the
  // trajectories that may are scored exactly.
  auto bar = [&]() { return best.cost < 0 || best.yv != 0.0 ? std::numeric_limits<double>::infinity() : best.cost; };

  if (!escaping_) {
    // Every forward (and strafing) sample, validity and progress exact but the outline costs of
    // steps over no lethal or unknown cell deferred: the cost is then a lower bound. The winner is
    // the valid sample of least exact cost, the earliest on a tie, as a sequential scan keeping the
    // first strict improvement would find; exact costs are computed in order of lower bound until
    // the bound exceeds the best exact cost, usually for a handful of the samples.
    struct Sample {
      double vx, vy, vth, cost;
      bool exact;
    };
    std::vector<Sample> samples;
    auto consider = [&](double vx, double vy, double vth) {
      generate(map, pose, vel, vx, vy, vth, impossible, comp, -std::numeric_limits<double>::infinity());
      if (comp.cost < 0) return;
      any_forward = any_forward || comp.xv > 0;
      // Farther along the plan and still on it (two cells) is progress too, whatever the
      // 4-connected distances say: they step by a cell either way along a diagonal.
      if (comp.xv > 0 && !progressing &&
          (comp.progress < progress_now - 1e-9 ||
           (along_now >= 0 && !comp.points.empty() && alongPlan(comp.points.back().head<2>()) > along_now))) {
        progressing = true;
      }
      samples.push_back({vx, vy, vth, comp.cost, comp.cost_exact});
    };
    double vx_samp = min_vx;
    for (int i = 0; i < p.vx_samples; ++i) {
      consider(vx_samp, 0.0, 0.0);  // straight ahead, always tried
      double vth_samp = min_vth;
      for (int j = 0; j < p.vtheta_samples - 1; ++j) {
        consider(vx_samp, 0.0, vth_samp);
        vth_samp += dvth;
      }
      vx_samp += dvx;
    }
    if (p.holonomic_robot) {
      for (double vy : {0.1, -0.1}) consider(0.1, vy, 0.0);
    }
    if (!progressing && spun_ > 2.0 * M_PI) {
      // A full circle on the spot showed no progress; another would show nothing new.
      for (const Sample& s : samples) progressing = progressing || s.vx > 0;
    }
    std::vector<std::size_t> order(samples.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return samples[a].cost < samples[b].cost; });
    std::size_t winner = samples.size();
    double winner_cost = std::numeric_limits<double>::infinity();
    for (std::size_t k : order) {
      Sample& c = samples[k];
      if (c.cost > winner_cost || (c.cost == winner_cost && k > winner)) continue;  // cannot win (bound only grows)
      if (!c.exact) {
        generate(map, pose, vel, c.vx, c.vy, c.vth, impossible, comp);
        c.cost = comp.cost;
        c.exact = true;
      }
      if (c.cost < winner_cost || (c.cost == winner_cost && k < winner)) {
        winner = k;
        winner_cost = c.cost;
      }
    }
    if (winner < samples.size()) {
      const Sample& c = samples[winner];
      generate(map, pose, vel, c.vx, c.vy, c.vth, impossible, best);  // its points, and its exact cost again
    }
  }

  // The goal distance heading_lookahead ahead of a trajectory's end (how well it faces the goal);
  // +inf when that point is off the map or the trajectory empty.
  auto goalDistanceAhead = [&](const Trajectory& t) {
    if (t.points.empty()) return std::numeric_limits<double>::infinity();
    const Eigen::Vector3d& e = t.points.back();
    const Cell ahead = map.worldToCell({e.x() + p.heading_lookahead * std::cos(e.z()), e.y() + p.heading_lookahead * std::sin(e.z())});
    return map.contains(ahead) ? static_cast<double>(goal_grid_.at(ahead)) : std::numeric_limits<double>::infinity();
  };

  // Rotating in place: towards the plan kTurnLookahead_m ahead (the rotation that ends facing it
  // most nearly), or, without a plan in sight, towards where the goal distance a heading_lookahead
  // ahead is smallest (ROS's rule). ROS's rule alone compares the goal distances of cells beside
  // the robot, which around obstacles can favour turning away from the plan; the oscillation flags
  // then forbid turning back, and the robot turned a full circle before it could follow the plan.
  Eigen::Vector2d turn_to;
  const bool aim = planAhead(pose.head<2>(), kTurnLookahead_m, &turn_to) && (turn_to - pose.head<2>()).norm() > 2.0 * map.resolution();
  auto turnScore = [&](const Trajectory& t) {
    if (!aim || t.points.empty()) return goalDistanceAhead(t);
    const Eigen::Vector3d& e = t.points.back();
    return std::abs(normalizeAngle(std::atan2(turn_to.y() - e.y(), turn_to.x() - e.x()) - e.z()));
  };
  if (!escaping_ && aim && !any_forward &&
      std::abs(normalizeAngle(std::atan2(turn_to.y() - pose.y(), turn_to.x() - pose.x()) - pose.z())) < kFacingPlan_rad) {
    // Facing the plan and no forward move fits: the robot stands where the way ahead is too tight
    // from its pose, though not from the plan's cells (the plan keeps the footprint clear at cell
    // centres; the robot is beside them). Turning on the spot shows nothing new, and in clutter
    // the robot turned on through a full circle; backing up, still facing the way, gives it the
    // room to come onto the plan. Escape mode is not entered: it would forbid driving on.
    generate(map, pose, vel, p.escape_vel, 0.0, 0.0, std::numeric_limits<double>::infinity(), comp);
    if (comp.cost >= 0) {
      resetFlagsIfMoved(pose);
      comp.cost = std::max(comp.cost, 1.0);
      return comp;
    }
  }
  double heading_dist = std::numeric_limits<double>::max();
  double vth_samp = min_vth;
  for (int i = 0; i < p.vtheta_samples && (!progressing || facing_away); ++i) {
    const double limited = vth_samp > 0 ? std::max(vth_samp, p.min_in_place_vel_theta) : std::min(vth_samp, -p.min_in_place_vel_theta);
    generate(map, pose, vel, 0.0, 0.0, limited, impossible, comp,
             facing_away ? std::numeric_limits<double>::infinity() : bar());  // exact: it may win on heading alone
    if (comp.cost >= 0 && (facing_away || comp.cost <= best.cost || best.cost < 0 || best.yv != 0.0) &&
        std::abs(vth_samp) > dvth) {
      const double d = turnScore(comp);
      if (d < heading_dist && ((vth_samp < 0 && !stuck_left_) || (vth_samp > 0 && !stuck_right_))) {
        std::swap(best, comp);
        heading_dist = d;
      }
    }
    vth_samp += dvth;
  }
  if (best.cost >= 0) {
    updateOscillationFlags(pose, best);
    return best;
  }

  if (p.holonomic_robot) {
    for (double vy : p.y_vels) {
      generate(map, pose, vel, 0.0, vy, 0.0, impossible, comp, bar());
      if (comp.cost >= 0 && (comp.cost <= best.cost || best.cost < 0)) {
        const double d = goalDistanceAhead(comp);
        if (d < heading_dist && ((vy > 0 && !stuck_left_strafe_) || (vy < 0 && !stuck_right_strafe_))) {
          std::swap(best, comp);
          heading_dist = d;
        }
      }
    }
    if (best.cost >= 0) {
      // ROS swaps left and right in this branch; the first branch's bookkeeping is the intended one.
      updateOscillationFlags(pose, best);
      return best;
    }
  }

  // Nothing forward, no turn, no strafe: back up at escape_vel. ROS backs up even when that
  // collides; here backing up must itself be collision-free, though it may leave the cells that
  // have a path distance (that is how a robot gets out of an inscribed pocket).
  generate(map, pose, vel, p.escape_vel, 0.0, 0.0, std::numeric_limits<double>::infinity(), comp);
  if (comp.cost < 0) {
    resetFlagsIfMoved(pose);
    best.cost = -1.0;  // boxed in: no safe command at all
    return best;
  }
  if (!escaping_) {
    escape_ = pose.head<2>();
    escape_theta_ = pose.z();
    escaping_ = true;
  }
  resetFlagsIfMoved(pose);
  comp.cost = std::max(comp.cost, 1.0);
  return comp;
}

}  // namespace core
}  // namespace mbot
