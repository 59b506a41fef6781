// Bindings of footprints and the local planner.
#include "bindings.h"

#include <tuple>

#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/local_planner.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindLocalPlanner(py::module& m) {
  m.def("_circle_footprint", &mbot::core::circleFootprint, py::arg("radius"));
  m.def("_pad_footprint", &mbot::core::padFootprint, py::arg("footprint"), py::arg("padding"));
  m.def("_inscribed_radius", &mbot::core::inscribedRadius, py::arg("footprint"));
  m.def("_circumscribed_radius", &mbot::core::circumscribedRadius, py::arg("footprint"));
  m.def("_validate_footprint", &mbot::core::validateFootprint, py::arg("footprint"));

  using mbot::core::LocalPlannerParams;
  py::class_<LocalPlannerParams>(m, "_LocalPlannerParams")
      .def(py::init<>())
      .def_readwrite("acc_lim_x", &LocalPlannerParams::acc_lim_x)
      .def_readwrite("acc_lim_y", &LocalPlannerParams::acc_lim_y)
      .def_readwrite("acc_lim_theta", &LocalPlannerParams::acc_lim_theta)
      .def_readwrite("max_vel_x", &LocalPlannerParams::max_vel_x)
      .def_readwrite("min_vel_x", &LocalPlannerParams::min_vel_x)
      .def_readwrite("max_vel_theta", &LocalPlannerParams::max_vel_theta)
      .def_readwrite("min_vel_theta", &LocalPlannerParams::min_vel_theta)
      .def_readwrite("min_in_place_vel_theta", &LocalPlannerParams::min_in_place_vel_theta)
      .def_readwrite("escape_vel", &LocalPlannerParams::escape_vel)
      .def_readwrite("sim_time", &LocalPlannerParams::sim_time)
      .def_readwrite("sim_granularity", &LocalPlannerParams::sim_granularity)
      .def_readwrite("angular_sim_granularity", &LocalPlannerParams::angular_sim_granularity)
      .def_readwrite("vx_samples", &LocalPlannerParams::vx_samples)
      .def_readwrite("vtheta_samples", &LocalPlannerParams::vtheta_samples)
      .def_readwrite("path_distance_bias", &LocalPlannerParams::path_distance_bias)
      .def_readwrite("goal_distance_bias", &LocalPlannerParams::goal_distance_bias)
      .def_readwrite("occdist_scale", &LocalPlannerParams::occdist_scale)
      .def_readwrite("meter_scoring", &LocalPlannerParams::meter_scoring)
      .def_readwrite("heading_lookahead", &LocalPlannerParams::heading_lookahead)
      .def_readwrite("heading_scoring", &LocalPlannerParams::heading_scoring)
      .def_readwrite("heading_scoring_timestep", &LocalPlannerParams::heading_scoring_timestep)
      .def_readwrite("oscillation_reset_dist", &LocalPlannerParams::oscillation_reset_dist)
      .def_readwrite("escape_reset_dist", &LocalPlannerParams::escape_reset_dist)
      .def_readwrite("escape_reset_theta", &LocalPlannerParams::escape_reset_theta)
      .def_readwrite("holonomic_robot", &LocalPlannerParams::holonomic_robot)
      .def_readwrite("dwa", &LocalPlannerParams::dwa)
      .def_readwrite("simple_attractor", &LocalPlannerParams::simple_attractor)
      .def_readwrite("y_vels", &LocalPlannerParams::y_vels)
      .def_readwrite("sim_period", &LocalPlannerParams::sim_period);

  using mbot::core::LocalPlanner;
  py::class_<LocalPlanner>(m, "_LocalPlanner")
      .def(py::init<const LocalPlannerParams&, const mbot::core::Footprint&>(), py::arg("params"), py::arg("footprint"))
      .def("set_plan", &LocalPlanner::setPlan, py::arg("plan"))
      .def(
          "find_best_path",
          [](LocalPlanner& lp, const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity) {
            mbot::core::Trajectory t;
            {
              py::gil_scoped_release release;
              t = lp.findBestPath(map, pose, velocity);
            }
            return py::make_tuple(Eigen::Vector3d(t.xv, t.yv, t.thetav), t.cost, t.points);
          },
          py::arg("costmap"), py::arg("pose"), py::arg("velocity"))
      .def("score_trajectory", &LocalPlanner::scoreTrajectory, py::arg("costmap"), py::arg("pose"), py::arg("velocity"),
           py::arg("command"))
      .def(
          "simulate",
          [](const LocalPlanner& lp, const Costmap& map, const Eigen::Vector3d& pose, const Eigen::Vector3d& velocity,
             const Eigen::Vector3d& command) {
            const mbot::core::Trajectory t = lp.simulate(map, pose, velocity, command);
            return py::make_tuple(t.cost, t.progress, t.points);
          },
          py::arg("costmap"), py::arg("pose"), py::arg("velocity"), py::arg("command"))
      .def("progress_at", &LocalPlanner::progressAt, py::arg("costmap"), py::arg("pose"))
      .def("update_grids", &LocalPlanner::updateGrids, py::arg("costmap"), py::arg("pose"))
      .def("reset_oscillation", &LocalPlanner::resetOscillation)
      .def("set_shortcuts", &mbot::core::LocalPlanner::setShortcuts, py::arg("on"),
           "false: every footprint by its full outline walk (the reference)")
      .def_property_readonly("local_goal", [](const LocalPlanner& lp) { return Eigen::Vector2d(lp.localGoal()); })
      .def_property_readonly("escaping", &LocalPlanner::escaping)
      .def("path_distances", [](const LocalPlanner& lp, const Costmap& map) {
        py::array_t<float> out({map.height(), map.width()});
        const auto& v = lp.pathGrid().values();
        if (v.size() != map.costs().size()) throw std::invalid_argument("path_distances: no grid for this costmap yet");
        std::copy(v.begin(), v.end(), out.mutable_data());
        return out;
      });
}

}  // namespace bindings
}  // namespace mbot
