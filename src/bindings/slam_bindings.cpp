// Bindings of the SLAM backends and their parameters (offline tools and tests; the node is roscpp).
#include "bindings.h"

#include <array>
#include <optional>
#include <string>
#include <tuple>

#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/rbpf_slam.h"
#include "mbot_slam_navigation/core/motion_model.h"
#include "mbot_slam_navigation/core/scan_matcher.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindSlam(py::module& m) {
  py::class_<mbot::core::MotionModelParams>(m, "_MotionModelParams")
      .def(py::init<>())
      .def_readwrite("srr", &mbot::core::MotionModelParams::srr)
      .def_readwrite("srt", &mbot::core::MotionModelParams::srt)
      .def_readwrite("str", &mbot::core::MotionModelParams::str)
      .def_readwrite("stt", &mbot::core::MotionModelParams::stt);
  using mbot::core::ScanMatcherParams;
  py::class_<ScanMatcherParams>(m, "_ScanMatcherParams")
      .def(py::init<>())
      .def_readwrite("sigma", &ScanMatcherParams::sigma)
      .def_readwrite("kernel_size", &ScanMatcherParams::kernel_size)
      .def_readwrite("lstep", &ScanMatcherParams::lstep)
      .def_readwrite("astep", &ScanMatcherParams::astep)
      .def_readwrite("iterations", &ScanMatcherParams::iterations)
      .def_readwrite("lsigma", &ScanMatcherParams::lsigma)
      .def_readwrite("lskip", &ScanMatcherParams::lskip)
      .def_readwrite("max_urange", &ScanMatcherParams::max_urange)
      .def_readwrite("max_range", &ScanMatcherParams::max_range)
      .def_readwrite("laser_pose", &ScanMatcherParams::laser_pose);
  m.def("scan_odometry_motion", &mbot::core::scanOdometryMotion,
        "The motion noise the filter takes on scan odometry unless the user sets it (rbpf_slam.h).");
  using mbot::core::RbpfParams;
  py::class_<RbpfParams>(m, "_RbpfParams")
      .def(py::init<>())
      .def_readwrite("particles", &RbpfParams::particles)
      .def_readwrite("linear_update", &RbpfParams::linear_update)
      .def_readwrite("angular_update", &RbpfParams::angular_update)
      .def_readwrite("temporal_update", &RbpfParams::temporal_update)
      .def_readwrite("resample_threshold", &RbpfParams::resample_threshold)
      .def_readwrite("ogain", &RbpfParams::ogain)
      .def_readwrite("minimum_score", &RbpfParams::minimum_score)
      .def_readwrite("llsamplerange", &RbpfParams::llsamplerange)
      .def_readwrite("llsamplestep", &RbpfParams::llsamplestep)
      .def_readwrite("lasamplerange", &RbpfParams::lasamplerange)
      .def_readwrite("lasamplestep", &RbpfParams::lasamplestep)
      .def_readwrite("delta", &RbpfParams::delta)
      .def_readwrite("xmin", &RbpfParams::xmin)
      .def_readwrite("ymin", &RbpfParams::ymin)
      .def_readwrite("xmax", &RbpfParams::xmax)
      .def_readwrite("ymax", &RbpfParams::ymax)
      .def_readwrite("seed", &RbpfParams::seed)
      .def_readwrite("motion", &RbpfParams::motion)
      .def_readwrite("matcher", &RbpfParams::matcher)
      .def_readwrite("scan_odometry", &RbpfParams::scan_odometry)
      .def_readwrite("threads", &RbpfParams::threads)
      .def_readwrite("best_switch_margin", &RbpfParams::best_switch_margin)
      .def_readwrite("tracking", &RbpfParams::tracking)
      .def("share_with", &RbpfParams::shareWith, py::arg("graph"),
           "Gives the graph (or the track) what both backends share: matcher, angularUpdate, temporalUpdate, delta, extent.")
      .def("validate", &RbpfParams::validate);
  // Both backends share the SlamBackend methods, bound once on the base class.
  using mbot::core::SlamBackend;
  py::class_<SlamBackend>(m, "_SlamBackend")
      .def(
          "process_scan",
          [](SlamBackend& s, const Eigen::Vector3d& odom, double angle_min, double angle_increment, double range_min,
             double range_max, const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges,
             double time) {
            const LaserScan scan = toScan(angle_min, angle_increment, range_min, range_max, ranges);
            py::gil_scoped_release release;
            return s.processScan(odom, scan, time);
          },
          py::arg("odom"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"),
          py::arg("range_max"), py::arg("ranges"), py::arg("time"))
      .def("current_pose", &SlamBackend::currentPose)
      .def("trajectory",
           [](const SlamBackend& s) {
             const auto traj = s.trajectory();
             py::array_t<double> out({static_cast<py::ssize_t>(traj.size()), static_cast<py::ssize_t>(7)});
             auto o = out.mutable_unchecked<2>();
             for (std::size_t i = 0; i < traj.size(); ++i) {
               o(i, 0) = traj[i].time_s;
               for (int k = 0; k < 3; ++k) {
                 o(i, 1 + k) = traj[i].pose[k];
                 o(i, 4 + k) = traj[i].odom[k];
               }
             }
             return out;
           })
      .def("occupancy",
           [](const SlamBackend& s, double occ_thresh) {
             mbot::core::OccupancyImage img;
             {
               py::gil_scoped_release release;
               img = s.occupancy(occ_thresh);
             }
             py::array_t<int8_t> data({img.height, img.width});
             std::copy(img.data.begin(), img.data.end(), data.mutable_data());
             return py::make_tuple(data, img.origin, img.resolution);
           },
           py::arg("occ_thresh") = 0.25)
      .def_property_readonly("updates", &SlamBackend::updates);
  using mbot::core::RbpfSlam;
  py::class_<RbpfSlam, SlamBackend>(m, "_RbpfSlam")
      .def(py::init<const RbpfParams&>())
      .def("pose_entropy", &RbpfSlam::poseEntropy)
      .def_property_readonly("resamples", &RbpfSlam::resamples)
      .def_property_readonly("last_neff", &RbpfSlam::lastNeff)
      .def("particle_poses", [](const RbpfSlam& s) {
        std::vector<Eigen::Vector3d> out;
        for (const auto& p : s.particles()) out.push_back(p.pose);
        return out;
      })
      .def("map_memory", [](const RbpfSlam& s) {
        // (bytes of distinct patches held by all particles, bytes if none were shared)
        std::unordered_set<const void*> distinct;
        long referenced = 0;
        for (const auto& p : s.particles()) {
          p.map.collectPatches(distinct);
          referenced += p.map.allocatedPatches();
        }
        return py::make_tuple(distinct.size() * mbot::core::SlamGrid::kPatchBytes,
                              referenced * mbot::core::SlamGrid::kPatchBytes);
      });
  using mbot::core::GraphSlamParams;
  py::class_<GraphSlamParams>(m, "_GraphSlamParams")
      .def(py::init<>())
      .def_readwrite("linear_update", &GraphSlamParams::linear_update)
      .def_readwrite("angular_update", &GraphSlamParams::angular_update)
      .def_readwrite("temporal_update", &GraphSlamParams::temporal_update)
      .def_readwrite("delta", &GraphSlamParams::delta)
      .def_readwrite("xmin", &GraphSlamParams::xmin)
      .def_readwrite("ymin", &GraphSlamParams::ymin)
      .def_readwrite("xmax", &GraphSlamParams::xmax)
      .def_readwrite("ymax", &GraphSlamParams::ymax)
      .def_readwrite("matcher", &GraphSlamParams::matcher)
      .def_readwrite("match_max_range", &GraphSlamParams::match_max_range)
      .def_readwrite("match_sigma", &GraphSlamParams::match_sigma)
      .def_readwrite("local_match_sigma", &GraphSlamParams::local_match_sigma)
      .def_readwrite("local_map_nodes", &GraphSlamParams::local_map_nodes)
      .def_readwrite("local_search_window", &GraphSlamParams::local_search_window)
      .def_readwrite("local_search_sigmas", &GraphSlamParams::local_search_sigmas)
      .def_readwrite("local_search_max_window", &GraphSlamParams::local_search_max_window)
      .def_readwrite("local_search_angle", &GraphSlamParams::local_search_angle)
      .def_readwrite("local_min_score", &GraphSlamParams::local_min_score)
      .def_readwrite("local_prior_margin", &GraphSlamParams::local_prior_margin)
      .def_readwrite("local_prior_weight", &GraphSlamParams::local_prior_weight)
      .def_readwrite("local_prior_points", &GraphSlamParams::local_prior_points)
      .def_readwrite("local_visible_only", &GraphSlamParams::local_visible_only)
      .def_readwrite("submap_nodes", &GraphSlamParams::submap_nodes)
      .def_readwrite("loop_search_radius", &GraphSlamParams::loop_search_radius)
      .def_readwrite("loop_search_growth", &GraphSlamParams::loop_search_growth)
      .def_readwrite("loop_search_max_radius", &GraphSlamParams::loop_search_max_radius)
      .def_readwrite("loop_search_reach", &GraphSlamParams::loop_search_reach)
      .def_readwrite("loop_search_angle", &GraphSlamParams::loop_search_angle)
      .def_readwrite("loop_min_response", &GraphSlamParams::loop_min_response)
      .def_readwrite("loop_ambiguity", &GraphSlamParams::loop_ambiguity)
      .def_readwrite("loop_sigma_distance", &GraphSlamParams::loop_sigma_distance)
      .def_readwrite("loop_visible_shift", &GraphSlamParams::loop_visible_shift)
      .def_readwrite("local_visible_side", &GraphSlamParams::local_visible_side)
      .def_readwrite("loop_candidates", &GraphSlamParams::loop_candidates)
      .def_readwrite("loop_recent_submap", &GraphSlamParams::loop_recent_submap)
      .def_readwrite("loop_reject_chi2", &GraphSlamParams::loop_reject_chi2)
      .def_readwrite("edge_sigma_xy", &GraphSlamParams::edge_sigma_xy)
      .def_readwrite("edge_sigma_theta", &GraphSlamParams::edge_sigma_theta)
      .def_readwrite("cauchy_scale", &GraphSlamParams::cauchy_scale)
      .def_readwrite("redundant_distance", &GraphSlamParams::redundant_distance)
      .def_readwrite("redundant_angle", &GraphSlamParams::redundant_angle)
      .def_readwrite("keep_trimmed_scans", &GraphSlamParams::keep_trimmed_scans)
      .def_readwrite("keep_scan_poses", &GraphSlamParams::keep_scan_poses)
      .def_readwrite("loop_solve_chi2", &GraphSlamParams::loop_solve_chi2)
      .def_readwrite("background", &GraphSlamParams::background)
      .def("validate", &GraphSlamParams::validate);
  using mbot::core::GraphSlam;
  py::class_<GraphSlam, SlamBackend>(m, "_GraphSlam")
      .def(py::init<const GraphSlamParams&>())
      .def("flush", &GraphSlam::flush, py::call_guard<py::gil_scoped_release>())
      .def("stats",
           [](const GraphSlam& s) {
             const auto st = s.stats();
             py::dict d;
             d["nodes"] = st.nodes;
             d["local_match_failures"] = st.local_match_failures;
             d["innovation_rms"] = st.innovation_rms;
             d["pinned_innovation_rms"] = st.pinned_innovation_rms;
             d["odometry_trust"] = st.odometry_trust;
             d["match_weakest_m"] = st.match_weakest_m;
             d["prior_weight"] = st.prior_weight;
             d["search_window_m"] = st.search_window_m;
             d["loop_attempts"] = st.loop_attempts;
             d["loop_closures"] = st.loop_closures;
             d["loop_rejected_ambiguous"] = st.loop_rejected_ambiguous;
             d["loop_rejected_inconsistent"] = st.loop_rejected_inconsistent;
             d["optimizations"] = st.optimizations;
             d["last_optimization_ms"] = st.last_optimization_ms;
             d["search_radius_m"] = st.search_radius_m;
             d["redundant_nodes"] = st.redundant_nodes;
             d["trimmed_nodes"] = st.trimmed_nodes;
             d["submaps"] = st.submaps;
             d["submaps_skipped"] = st.submaps_skipped;
             d["submap_bytes"] = st.submap_bytes;
             d["closures_accepted"] = st.closures_accepted;
             d["merged_nodes"] = st.merged_nodes;
             d["closures_moved"] = st.closures_moved;
             d["closures_remeasured"] = st.closures_remeasured;
             d["closures_partial"] = st.closures_partial;
             d["closures_recent"] = st.closures_recent;
             d["closures_unsolved"] = st.closures_unsolved;
             d["closure_backlog"] = st.closure_backlog;
             d["closure_backlog_max"] = st.closure_backlog_max;
             return d;
           })
      .def("scan_poses",
           [](const GraphSlam& s) {
             const auto poses = s.scanPoses();
             py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), static_cast<py::ssize_t>(4)});
             auto o = out.mutable_unchecked<2>();
             for (std::size_t i = 0; i < poses.size(); ++i) {
               o(i, 0) = poses[i].first;
               for (int k = 0; k < 3; ++k) o(i, 1 + k) = poses[i].second[k];
             }
             return out;
           })
      .def("edges",
           [](const GraphSlam& s) {
             // (from, to, x, y, theta, is_closure): every edge's measurement, the pose of `to` in `from`'s frame
             std::vector<std::tuple<int, int, double, double, double, bool>> out;
             for (const auto& e : s.edges()) {
               out.emplace_back(e.from, e.to, e.measurement.x(), e.measurement.y(), e.measurement.z(), e.robust);
             }
             return out;
           })
      // Sessions (graph_slam.h): save to / load from <path> (the .posegraph file itself).
      .def(
          "save_session",
          [](GraphSlam& s, const std::string& path) {
            py::gil_scoped_release release;
            return mbot::core::saveSessionFile(s, path);
          },
          py::arg("path"))
      .def_static(
          "load_session",
          [](const std::string& path, const GraphSlamParams& params) {
            std::string notes;
            std::unique_ptr<GraphSlam> slam;
            try {
              slam = GraphSlam::loadSession(mbot::core::readSessionFile(path), params, &notes);
            } catch (const mbot::core::SessionError& e) {
              throw mbot::core::SessionError("cannot load the session " + path + ": " + e.what());
            }
            return std::make_pair(std::move(slam), notes);
          },
          py::arg("path"), py::arg("params"))
      .def(
          "resume",
          [](GraphSlam& s, std::optional<std::array<double, 3>> pose, bool localization) {
            std::optional<Eigen::Vector3d> p;
            if (pose) p = Eigen::Vector3d((*pose)[0], (*pose)[1], (*pose)[2]);
            s.resume(p, localization);
          },
          py::arg("pose") = py::none(), py::arg("localization") = false)
      .def("resuming", &GraphSlam::resuming)
      .def("resume_failure", &GraphSlam::resumeFailure)
      .def("first_pose", [](const GraphSlam& s) {
        const Eigen::Vector3d p = s.firstPose();
        return std::make_tuple(p.x(), p.y(), p.z());
      });
  py::register_exception<mbot::core::SessionError>(m, "SessionError", PyExc_ValueError);
  m.def("session_path", &mbot::core::sessionPath, py::arg("filename"));
}

}  // namespace bindings
}  // namespace mbot
