// Closed loop through a door: the global planner's plan, TrajectoryController at the exploration
// tutorial's settings, and the simulator's drive (its wheel acceleration limit, its collisions), past
// the home's kitchen door (0.9 m wide between two 0.1 m jambs). The simulator's robot is the mbot's
// collision hull (its wheels stand 2.5 mm out of the 0.2 m base); the costmap knows the footprint as
// robot_radius 0.2 padded by 0.01. The robot must get through, and touch a jamb rarely if ever.
// DOORWAY_TRACE=1 prints every control cycle.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <gtest/gtest.h>

#include "mbot_slam_navigation/core/diff_drive.h"
#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/global_planner.h"
#include "mbot_slam_navigation/core/inflation_layer.h"
#include "mbot_slam_navigation/core/trajectory_controller.h"
#include "tutorial_planner_params.h"

using namespace mbot::core;
using mbot::core::test_fixtures::tutorialParams;

namespace {
struct Box {
  double x0, x1, y0, y1;
};

// The home's walls and furniture around the kitchen door (tools/make_worlds.py): wall centre lines
// thickened by 0.1 m and lengthened by 0.05 m at each end, as the world file has them.
const std::vector<Box>& kitchenDoor() {
  static const std::vector<Box> boxes = {
      {1.15, 2.65, -3.65, -3.55},  // kitchen | dining, west of the door (x 2.6 .. 3.5)
      {3.45, 4.55, -3.65, -3.55},  // east of the door
      {1.15, 1.25, -6.05, -3.55},  // kitchen | living room
      {1.15, 1.25, -3.65, -3.25},  // dining | living room, south of the opening
      {1.15, 1.25, -1.55, -1.15},  // north of the opening
      {1.15, 4.55, -1.25, -1.15},  // dining | bathroom
      {4.45, 4.55, -6.05, -1.15},  // east wall
      {1.15, 4.55, -6.05, -5.95},  // south wall
      {3.85, 4.45, -5.8, -3.8},    // kitchen counter
      {3.2, 4.0, -3.0, -1.8},      // dining table
  };
  return boxes;
}

// The mbot's collision hull in its base frame (sim/urdf_robot.py of urdf/xacro/robot.xacro).
std::vector<Eigen::Vector2d> mbotHull() {
  return {{-0.2, 0.0},           {-0.18477591, -0.07653669}, {-0.14142136, -0.14142136}, {-0.06, -0.2025},
          {0.06, -0.2025},       {0.14142136, -0.14142136},  {0.18477591, -0.07653669},  {0.2, 0.0},
          {0.18477591, 0.07653669}, {0.14142136, 0.14142136}, {0.06, 0.2025},             {-0.06, 0.2025},
          {-0.14142136, 0.14142136}, {-0.18477591, 0.07653669}};
}

// The world the simulator collides with.
World2D worldOf(const std::vector<Box>& boxes) {
  World2D world;
  for (const Box& b : boxes) world.addBox({0.5 * (b.x0 + b.x1), 0.5 * (b.y0 + b.y1)}, 0.0, b.x1 - b.x0, b.y1 - b.y0);
  return world;
}

// The boxes as lethal cells (every cell a box overlaps, as laser hits on its faces mark them),
// inflated as the mbot's costmaps are.
Costmap costmapOf(const std::vector<Box>& boxes, const Eigen::Vector2d& origin, double inscribed) {
  Costmap m(90, 110, 0.05, origin);
  for (int y = 0; y < m.height(); ++y) {
    for (int x = 0; x < m.width(); ++x) {
      const double cx0 = origin.x() + x * 0.05, cy0 = origin.y() + y * 0.05;
      for (const Box& b : boxes) {
        if (cx0 < b.x1 && cx0 + 0.05 > b.x0 && cy0 < b.y1 && cy0 + 0.05 > b.y0) m.setCost({x, y}, cost::kLethal);
      }
    }
  }
  InflationParams ip;
  ip.inscribed_radius = inscribed;
  ip.inflation_radius = 0.6;
  ip.cost_scaling_factor = 10.0;
  inflate(m, ip);
  return m;
}

struct Outcome {
  bool reached = false, touched = false;
  int cycles = 0, invalid_cycles = 0;
  double min_clearance = 1e9;
};

// Drives from `start` to `goal` at 3 Hz for at most `max_cycles`; the command holds for a cycle.
Outcome drive(const Eigen::Vector3d& start, const Eigen::Vector2d& goal, const Eigen::Vector2d& origin) {
  const Footprint footprint = padFootprint(circleFootprint(0.2), 0.01);
  const Costmap map = costmapOf(kitchenDoor(), origin, inscribedRadius(footprint));
  GlobalPlanner planner;
  Outcome out;
  const Plan plan = planner.makePlan(map, start.head<2>(), goal);
  if (plan.status != PlanStatus::kOk) return out;
  LocalPlannerRosParams ros;
  ros.xy_goal_tolerance = 0.1;
  ros.yaw_goal_tolerance = 0.1;
  LocalPlannerParams params = tutorialParams();
  params.sim_period = 1.0 / 3.0;  // the tutorial's controller_frequency 3 Hz
  TrajectoryController controller(params, ros, footprint);
  const double goal_yaw = std::atan2(goal.y() - start.y(), goal.x() - start.x());
  controller.setPlan(plan.path, goal_yaw);
  // The simulator's drive: the mbot's wheels (urdf/xacro/mbot_base_gazebo.xacro) with their
  // acceleration limit, stepped at the simulator's 0.01 s; it stops where it touches.
  static const World2D world = worldOf(kitchenDoor());
  DiffDriveParams dp;
  dp.wheel_separation_m = 0.38;
  dp.wheel_diameter_m = 0.12;
  dp.wheel_acceleration_mps2 = 1.0;
  DiffDrive robot(dp, mbotHull(), start, 1);
  double now = 0.0;
  const bool trace = std::getenv("DOORWAY_TRACE") != nullptr;
  for (out.cycles = 0; out.cycles < 240; ++out.cycles) {
    const Eigen::Vector3d pose = robot.pose(), vel(robot.linearVelocity(), 0.0, robot.angularVelocity());
    const ControlResult r = controller.compute(map, pose, vel);
    if (trace) {
      std::printf("  %3d (%.3f, %.3f, %.2f) %s cmd (%.2f, %.2f) scale %.1f %s; footprint cost %d, centre cost %d\n",
                  out.cycles, pose.x(), pose.y(), pose.z(), r.valid ? "ok" : "INVALID", r.command.x(), r.command.z(),
                  r.footprint_scale, r.why.c_str(), footprintCost(map, pose, footprint, true),
                  map.cost(map.worldToCell(pose.head<2>())));
    }
    if (controller.reached()) {
      out.reached = true;
      break;
    }
    out.invalid_cycles += !r.valid;
    robot.command(r.valid ? r.command.x() : 0.0, r.valid ? r.command.z() : 0.0, now);
    for (int k = 0; k < 33; ++k, now += 0.01) {  // 1/3 s: the tutorial's controller_frequency 3 Hz
      if (robot.step(0.01, now, world)) {
        if (trace && !out.touched) std::printf("  touched at (%.3f, %.3f, %.2f)\n", robot.pose().x(), robot.pose().y(), robot.pose().z());
        out.touched = true;
      }
    }
  }
  return out;
}
}  // namespace

TEST(DoorwayDrive, ThroughTheKitchenDoorWithoutWedgingAgainstAJamb) {
  int runs = 0, touched = 0, stuck = 0;
  for (double ox : {0.0, 0.013, 0.041}) {  // where the cell borders fall matters
    const Eigen::Vector2d origin(0.5 + ox, -6.2 + ox * 0.7);
    for (const Eigen::Vector2d s : {Eigen::Vector2d(2.0, -2.6), Eigen::Vector2d(2.3, -3.1), Eigen::Vector2d(1.7, -3.2),
                                    Eigen::Vector2d(2.6, -2.2), Eigen::Vector2d(3.3, -3.3), Eigen::Vector2d(1.8, -2.0)}) {
      for (int h = 0; h < 8; ++h) {
        for (const Eigen::Vector2d g : {Eigen::Vector2d(2.93, -3.57), Eigen::Vector2d(2.9, -4.3), Eigen::Vector2d(2.58, -4.07)}) {
          const Outcome o = drive({s.x(), s.y(), -M_PI + h * M_PI / 4}, g, origin);
          ++runs;
          touched += o.touched;
          stuck += !o.reached;
          if (o.touched || !o.reached) {
            std::printf("start (%.2f, %.2f, %d/8) goal (%.2f, %.2f) origin +%.3f: %s%s after %d cycles (%d invalid)\n", s.x(),
                        s.y(), h, g.x(), g.y(), ox, o.touched ? "touched " : "", o.reached ? "reached" : "not reached",
                        o.cycles, o.invalid_cycles);
          }
        }
      }
    }
  }
  std::printf("%d runs: %d touched a jamb, %d did not reach the goal\n", runs, touched, stuck);
  // Before the outline took every cell it crosses, a round robot was checked as a ring and an
  // escape could not go deeper, 35 of 576 such runs (4 grid origins) wedged against the west jamb.
  EXPECT_EQ(stuck, 0);
  // The drive brakes at 1 m/s^2 where the tutorial's planner counts on 2.5, so a turn near a jamb
  // can end a millimetre or so from it: rarely, and never a wedge.
  EXPECT_LE(touched, runs / 100);
}
