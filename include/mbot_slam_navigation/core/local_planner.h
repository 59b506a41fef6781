// base_local_planner's TrajectoryPlanner (trajectory rollout, and DWA when `dwa`), ROS-free.
//
// Each control cycle samples velocity commands (vx, vtheta; plus strafes for holonomic robots),
// forward-simulates each for sim_time under the acceleration limits, and scores the trajectory
//   cost = path_distance_bias * path_dist + goal_distance_bias * goal_dist + occdist_scale * occ
// where path_dist / goal_dist are the 4-connected cell distances (MapGrid) from the trajectory's
// last point to the global plan / to the plan's last point inside the local costmap, and occ is the
// highest costmap value under the footprint along the trajectory. A trajectory is invalid (-1) if
// the footprint outline touches a lethal or unknown cell or leaves the map, and (-2) if it enters a
// cell with no path to the goal. With meter_scoring the two biases and occdist_scale are multiplied
// by the costmap resolution (as ROS's TrajectoryPlanner::reconfigure does), so the distances count
// in metres.
// Rotating in place (at least min_in_place_vel_theta, towards the goal) is considered when no
// forward trajectory gets closer to the plan and goal than the robot is now; then strafes
// (holonomic), then backing up at escape_vel, with ROS's oscillation flags (no turning back the
// way it just turned until it moved oscillation_reset_dist) and escape mode.
// One deliberate difference: ROS also lets an in-place rotation win whenever it merely scores
// lower than the best forward trajectory. Near a wall the occupancy term of every forward move
// grows faster than its distance terms shrink (with meter_scoring and the tutorials' biases), so
// ROS's robot spins in place there until move_base gives up; here a forward move that makes
// progress is always preferred to spinning on the spot. And progress includes moving farther along
// the plan while staying on it (within two cells): the distances are ROS's 4-connected ones, so
// where the plan runs diagonally away from the goal's row or column (leaving a doorway at 45
// degrees, say) no move lowers their sum, and ROS's robot, like ours before, turns on the spot
// until move_base gives up. Whatever the cause, a robot that has turned a full circle on the spot
// without finding progress takes its best forward move (a turn more would show it nothing new).
// The other way round: where the plan heading_lookahead ahead lies more than 60 degrees off the
// robot's heading, a valid rotation in place is taken even though a slow forward arc would make
// progress (before, the robot crawled sideways to such a plan at min_vel_x: the slow arcs end in
// the same cells, and the straight one wins the tie).
// Turning on the spot aims at the plan 0.5 m ahead (ROS: at the neighbouring cell of least goal
// distance, which around obstacles can point away from the plan). Facing the plan (within 20
// degrees) with no valid forward move, the robot backs up at escape_vel without entering escape
// mode instead of turning: the plan keeps the footprint clear at cell centres, and a robot beside
// them needs room to come onto it. The local goal is the last plan point that the robot can reach
// through the local costmap (ROS: the last one in the map, which may lie behind an obstacle only
// the local costmap has seen yet, and then no trajectory is valid).
//
// Frames: every pose is in the local costmap's global frame (x [m], y [m], yaw [rad]); velocities
// are in the robot frame (vx, vy [m/s], vtheta [rad/s]).
#pragma once

#include <limits>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/footprint.h"

namespace mbot {
namespace core {

/// Parameter names, and defaults, of TrajectoryPlannerROS as it behaves in ROS: the
/// dynamic_reconfigure defaults (BaseLocalPlanner.cfg), which override the constructor's.
struct LocalPlannerParams {
  double acc_lim_x = 2.5, acc_lim_y = 2.5, acc_lim_theta = 3.2;  ///< [m/s^2], [rad/s^2]
  double max_vel_x = 0.55, min_vel_x = 0.0;                       ///< [m/s]
  double max_vel_theta = 1.0, min_vel_theta = -1.0;               ///< [rad/s]
  double min_in_place_vel_theta = 0.4;                            ///< [rad/s]
  double escape_vel = -0.1;                                       ///< [m/s] backing-up speed
  double sim_time = 1.7;                                          ///< [s]
  double sim_granularity = 0.025;                                 ///< [m] step along a trajectory
  double angular_sim_granularity = 0.025;                         ///< [rad]
  int vx_samples = 20, vtheta_samples = 20;
  double path_distance_bias = 0.6, goal_distance_bias = 0.8, occdist_scale = 0.01;
  bool meter_scoring = false;
  double heading_lookahead = 0.325;                               ///< [m]
  bool heading_scoring = false;
  double heading_scoring_timestep = 0.1;                          ///< [s]
  double oscillation_reset_dist = 0.05, escape_reset_dist = 0.10; ///< [m]
  double escape_reset_theta = 1.5707963267948966;                 ///< [rad]
  bool holonomic_robot = true;
  bool dwa = false;
  bool simple_attractor = false;
  std::vector<double> y_vels = {-0.3, -0.1, 0.1, -0.3};           ///< [m/s] (ROS's default string)
  double sim_period = 0.05;  ///< [s] 1 / controller_frequency: the DWA velocity window
  /// std::invalid_argument naming the parameter for values ROS would misbehave on.
  void validate() const;
};

struct Trajectory {
  double xv = 0.0, yv = 0.0, thetav = 0.0;  ///< the sampled command
  double cost = -1.0;                       ///< < 0: invalid (-1 collision, -2 no path to goal)
  double progress = 0.0;                    ///< the distance terms alone at the last point
  bool cost_exact = true;                   ///< false: `cost` is a lower bound (see generate)
  std::vector<Eigen::Vector3d> points;      ///< simulated poses (x, y, yaw)
};

/// MapGrid: 4-connected cell distances over a costmap to a set of target cells (0 on a target,
/// +1 per step), through cells that are not lethal, inscribed or unknown (except cells under the
/// robot). Unreached cells hold unreachable() = cells + 1, obstacle cells obstacle() = cells.
class DistanceGrid {
 public:
  void reset(const Costmap& map);
  /// Targets the plan's cells from its first point inside the map until it leaves it; returns
  /// false (and targets nothing) when no plan point is inside the map and known.
  bool setPath(const Costmap& map, const std::vector<Eigen::Vector2d>& plan);
  /// Targets the last plan point of the first stretch inside the map (the local goal).
  bool setLocalGoal(const Costmap& map, const std::vector<Eigen::Vector2d>& plan, Eigen::Vector2d* local_goal = nullptr);
  void markWithinRobot(const std::vector<Cell>& cells);
  /// Targets `cells` (the robot's own): the distances then say what the robot can reach.
  void setSources(const Costmap& map, const std::vector<Cell>& cells);
  double at(const Cell& c) const { return dist_[static_cast<std::size_t>(c.y) * width_ + c.x]; }
  double obstacle() const { return static_cast<double>(dist_.size()); }
  double unreachable() const { return static_cast<double>(dist_.size()) + 1.0; }
  const std::vector<float>& values() const { return dist_; }

 private:
  void propagate(const Costmap& map, std::vector<int>& queue);
  int width_ = 0;
  std::vector<float> dist_;
  std::vector<uint8_t> within_robot_;
  std::vector<uint8_t> target_;
};

/// The plan with points inserted so consecutive points are at most `resolution` apart (ROS's
/// adjustPlanResolution), so every cell it crosses becomes a target.
std::vector<Eigen::Vector2d> densifyPlan(const std::vector<Eigen::Vector2d>& plan, double resolution);

/// The cells covered by the footprint at `pose`: its outline and interior (costmap frame).
std::vector<Cell> footprintCells(const Costmap& map, const Eigen::Vector3d& pose, const Footprint& footprint);

class LocalPlanner {
 public:
  LocalPlanner(const LocalPlannerParams& params, const Footprint& footprint);
  const LocalPlannerParams& params() const { return params_; }
  const Footprint& footprint() const { return footprint_; }
  /// The footprint scale the last findBestPath used: 1, or less when the full footprint touched a
  /// lethal cell where the robot stood and a shrunken one let it move out (kEscapeScales).
  double lastFootprintScale() const { return footprint_scale_; }
  static constexpr double kEscapeScales[] = {0.9, 0.8, 0.7, 0.6, 0.5};
  /// Tried first where the costmap has boxes (cell_box): a box's margin is a centimetre.
  static constexpr double kBoxEscapeScales[] = {0.97, 0.94};
  /// [s] A trajectory is checked against boxes (cell_box) grown by the distance its footprint's
  /// farthest point moves in this time at the trajectory's speeds: the pose a command acts on is
  /// older than the command (the laser's, tf's and the planner's latency), and the base follows
  /// its command under acceleration limits. Whole cells have their rounding for that margin; a
  /// box's centimetre is less than 0.3 m/s drives in 0.1 s, so through a gap the robot clears by
  /// a centimetre or two it drives slowly.
  static constexpr double kBoxLatency = 0.1;
  /// [m] The distance from the robot's centre to the nearest lethal cell inside its footprint (its
  /// inscribed circle) at the last findBestPath; infinity when none. While there is one, no step of
  /// a trajectory may come nearer to it (see useEscapeFootprint).
  double lastObstacleInside() const { return inside_distance_; }

  /// The global plan (costmap frame, pruned to start near the robot).
  void setPlan(const std::vector<Eigen::Vector2d>& plan);
  /// One control cycle: the best trajectory from `pose` moving at `velocity`; cost < 0 when none
  /// is valid (the command is then zero).
  Trajectory findBestPath(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity);
  /// The cost of one command from `pose` (ROS's scoreTrajectory; uses the grids of the last
  /// findBestPath / updateGrids); >= 0 means the command is safe.
  double scoreTrajectory(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity,
                         const Eigen::Vector3d& command);
  /// The whole simulated trajectory of one command (for inspection and tests).
  Trajectory simulate(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity,
                      const Eigen::Vector3d& command) const;
  /// The distance terms at the robot's own cell (what a trajectory must beat to make progress).
  double progressAt(const Costmap& map, const Eigen::Vector3d& pose) const;
  /// Index along the plan (densified to the costmap's cells, as far as it stays on the local map)
  /// of the plan point nearest `point` [m], if one lies within two cells; -1 otherwise.
  int alongPlan(const Eigen::Vector2d& point) const;
  /// The plan point `lookahead` [m] along the plan (densified, on the local map) from the plan point
  /// nearest `point`, or the plan's last one; false without a plan on the local map.
  bool planAhead(const Eigen::Vector2d& point, double lookahead, Eigen::Vector2d* ahead) const;
  /// Recomputes the path and goal distance grids for `pose` without choosing a command.
  void updateGrids(const Costmap& map, const Eigen::Vector3d& pose);
  /// Caps the forward speed sampled at `max_vel_x` [m/s] (a speed zone); infinity lifts the cap.
  /// Never below min_vel_x.
  void setSpeedLimit(double max_vel_x) { speed_limit_ = max_vel_x; }
  double speedLimit() const { return speed_limit_; }
  /// Clears the oscillation and escape state (a new goal).
  void resetOscillation();
  /// Ends escape mode (the robot may drive forward again at once).
  void resetEscape() { escaping_ = false; }
  /// false: score every footprint by its full outline walk (the reference the shortcuts must
  /// match exactly; for tests and benchmarks).
  void setShortcuts(bool on) { shortcuts_ = on; }

  const DistanceGrid& pathGrid() const { return path_grid_; }
  const DistanceGrid& goalGrid() const { return goal_grid_; }
  const Eigen::Vector2d& localGoal() const { return local_goal_; }
  bool escaping() const { return escaping_; }

 private:
  /// Simulates and scores one command into `traj`. `exact_below`: the exact cost is only needed
  /// when it could be <= this (within findBestPath, a trajectory that cannot beat the best so far
  /// only needs its validity; its cost is then a lower bound above exact_below).
  void generate(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel, double vx_samp,
                double vy_samp, double vth_samp, double impossible_cost, Trajectory& traj,
                double exact_below = std::numeric_limits<double>::infinity()) const;
  double headingDiff(const Costmap& map, const Cell& cell, const Eigen::Vector3d& pose) const;
  Trajectory createTrajectories(const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& vel);
  void updateOscillationFlags(const Eigen::Vector3d& pose, const Trajectory& best);
  /// footprintCost, with an exact shortcut: when no cell of the square around the footprint's
  /// circumscribed circle has a cost above 0 (the summed-area table of non-zero cells built for
  /// this cycle says so in four lookups), every outline cell is free and the cost is 0.
  /// With `defer` (may be null), a footprint whose square holds no lethal or unknown cell is valid
  /// and its exact cost is left for later: *defer is set and a lower bound of it returned.
  int footprintCostAt(const Costmap& map, const Eigen::Vector3d& pose, bool* defer = nullptr, double box_margin = 0.0) const;
  void buildNonZeroTable(const Costmap& map);
  void resetFlagsIfMoved(const Eigen::Vector3d& pose);

  LocalPlannerParams params_;
  Footprint footprint_;
  double path_bias_, goal_bias_, occ_scale_;  // scaled by the resolution with meter_scoring (set per cycle)
  std::vector<Eigen::Vector2d> plan_;
  std::vector<Eigen::Vector2d> dense_plan_;  // plan_ at cell spacing, while on the local map (updateGrids)
  double dense_reach_ = 0.0;                 // [m] two cells
  bool goal_valid_ = false;
  Eigen::Vector2d final_goal_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d local_goal_ = Eigen::Vector2d::Zero();
  DistanceGrid path_grid_, goal_grid_;
  DistanceGrid reach_grid_;  // from the robot's cells: which plan points it can reach
  // Summed-area table of cells with a non-zero cost, (w + 1) x (h + 1); valid only inside
  // findBestPath, for the map it was called with.
  std::vector<int> nonzero_, blocking_;  // blocking_: cells that are lethal or unknown
  int table_w_ = 0, table_h_ = 0;
  bool table_valid_ = false, shortcuts_ = true;
  double box_latency_ = kBoxLatency;         // [s] kBoxLatency, or 0 where no move keeps its margin
  double circumscribed_ = 0.0;
  double footprint_scale_ = 1.0;
  double full_radius_ = 0.0;                 // circumscribed_ of the whole footprint while escaping
  uint8_t max_centre_cost_ = cost::kNoInformation;  // escaping: no step's centre cell may cost more
  // Escaping: the distance [m] from the centre to the nearest lethal cell within the whole
  // footprint's circumscribed radius where the robot stands (infinity: none); no step may bring
  // one nearer. Inside the inscribed radius every cell costs the same, so the centre cost alone
  // lets the robot drive on into a person who stands inside its footprint.
  double min_lethal_distance_ = std::numeric_limits<double>::infinity();
  double inside_distance_ = std::numeric_limits<double>::infinity();
  double nearestLethal(const Costmap& map, const Eigen::Vector2d& at, double within) const;
  /// Index of the densified plan point nearest `point` [m] within `within` [m] (the later one on a
  /// tie); -1 if none.
  int nearestPlanIndex(const Eigen::Vector2d& point, double within) const;
  /// Swaps in the escape footprint when the whole one touches a lethal cell at `pose` (see the
  /// .cpp); returns the whole footprint for restoreFootprint.
  Footprint useEscapeFootprint(const Costmap& map, const Eigen::Vector3d& pose);
  void restoreFootprint(const Footprint& full);
  // ROS's oscillation suppression and escape state.
  bool stuck_left_ = false, stuck_right_ = false, stuck_left_strafe_ = false, stuck_right_strafe_ = false;
  bool rotating_left_ = false, rotating_right_ = false, strafe_left_ = false, strafe_right_ = false;
  bool escaping_ = false;
  double speed_limit_ = std::numeric_limits<double>::infinity();  // [m/s] setSpeedLimit
  Eigen::Vector2d prev_ = Eigen::Vector2d::Zero(), escape_ = Eigen::Vector2d::Zero();
  double escape_theta_ = 0.0;
  // Turning on the spot: where it started and how far it has turned since [rad].
  Eigen::Vector2d spin_spot_ = Eigen::Vector2d::Zero();
  double spin_yaw_ = 0.0, spun_ = 0.0;
};

}  // namespace core
}  // namespace mbot
