// The one pybind11 module over the C++ core. Bound names are private (leading underscore); the
// typed wrappers in src/mbot_slam_navigation/ are what Python code imports. Conversions to and from
// numpy happen here, at the boundary, and nowhere else.
#include <tuple>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "mbot_slam_navigation/core/amcl.h"
#include "mbot_slam_navigation/core/bresenham.h"
#include "mbot_slam_navigation/core/diff_drive.h"
#include "mbot_slam_navigation/core/costmap.h"
#include "mbot_slam_navigation/core/footprint.h"
#include "mbot_slam_navigation/core/local_planner.h"
#include "mbot_slam_navigation/core/map_image.h"
#include "mbot_slam_navigation/core/obstacle_layer.h"
#include "mbot_slam_navigation/core/global_planner.h"
#include "mbot_slam_navigation/core/graph_slam.h"
#include "mbot_slam_navigation/core/grid_raycast.h"
#include "mbot_slam_navigation/core/inflation_layer.h"
#include "mbot_slam_navigation/core/occupancy_grid.h"
#include "mbot_slam_navigation/core/path_lengths.h"
#include "mbot_slam_navigation/core/rbpf_slam.h"
#include "mbot_slam_navigation/core/tour.h"
#include "mbot_slam_navigation/core/world2d.h"

namespace py = pybind11;

void bindNavigation(py::module& m);  // nav_bindings.cpp
using mbot::core::Cell;
using mbot::core::LaserScan;
using mbot::core::LogOddsModel;
using mbot::core::DiffDrive;
using mbot::core::DiffDriveParams;
using mbot::core::OccupancyGrid;
using mbot::core::Polygon;
using mbot::core::World2D;

namespace {

Cell toCell(const std::pair<int, int>& c) { return Cell{c.first, c.second}; }

LaserScan toScan(double angle_min, double angle_increment, double range_min, double range_max,
                 const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges) {
  LaserScan scan;
  scan.angle_min_rad = angle_min;
  scan.angle_increment_rad = angle_increment;
  scan.range_min_m = range_min;
  scan.range_max_m = range_max;
  scan.ranges_m.assign(ranges.data(), ranges.data() + ranges.size());
  return scan;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  bindNavigation(m);
  m.doc() = "C++ core of mbot_slam_navigation (private: use the wrappers in mbot_slam_navigation)";

  using mbot::core::Amcl;
  using mbot::core::AmclMap;
  using mbot::core::AmclParams;
  py::class_<AmclParams>(m, "_AmclParams")
      .def(py::init<>())
      .def_readwrite("min_particles", &AmclParams::min_particles)
      .def_readwrite("max_particles", &AmclParams::max_particles)
      .def_readwrite("kld_err", &AmclParams::kld_err)
      .def_readwrite("kld_z", &AmclParams::kld_z)
      .def_readwrite("recovery_alpha_slow", &AmclParams::recovery_alpha_slow)
      .def_readwrite("recovery_alpha_fast", &AmclParams::recovery_alpha_fast)
      .def_property(
          "odom_model", [](const AmclParams& p) { return p.odom_model == mbot::core::OdomModel::kDiff ? "diff" : "omni"; },
          [](AmclParams& p, const std::string& v) {
            if (v != "diff" && v != "omni") throw std::invalid_argument("odom_model must be diff or omni, not " + v);
            p.odom_model = v == "diff" ? mbot::core::OdomModel::kDiff : mbot::core::OdomModel::kOmni;
          })
      .def_readwrite("alpha1", &AmclParams::alpha1)
      .def_readwrite("alpha2", &AmclParams::alpha2)
      .def_readwrite("alpha3", &AmclParams::alpha3)
      .def_readwrite("alpha4", &AmclParams::alpha4)
      .def_readwrite("alpha5", &AmclParams::alpha5)
      .def_property(
          "laser_model",
          [](const AmclParams& p) { return p.laser_model == mbot::core::LaserModel::kBeam ? "beam" : "likelihood_field"; },
          [](AmclParams& p, const std::string& v) {
            if (v != "beam" && v != "likelihood_field") {
              throw std::invalid_argument("laser_model must be likelihood_field or beam, not " + v);
            }
            p.laser_model = v == "beam" ? mbot::core::LaserModel::kBeam : mbot::core::LaserModel::kLikelihoodField;
          })
      .def_readwrite("max_beams", &AmclParams::max_beams)
      .def_readwrite("z_hit", &AmclParams::z_hit)
      .def_readwrite("z_short", &AmclParams::z_short)
      .def_readwrite("z_max", &AmclParams::z_max)
      .def_readwrite("z_rand", &AmclParams::z_rand)
      .def_readwrite("sigma_hit", &AmclParams::sigma_hit)
      .def_readwrite("lambda_short", &AmclParams::lambda_short)
      .def_readwrite("likelihood_max_dist", &AmclParams::likelihood_max_dist)
      .def("validate", &AmclParams::validate);

  py::class_<AmclMap, std::shared_ptr<AmclMap>>(m, "_AmclMap")
      .def(py::init([](const py::array_t<int8_t, py::array::c_style | py::array::forcecast>& data, double resolution,
                       const Eigen::Vector2d& origin) {
             if (data.ndim() != 2) throw std::invalid_argument("data must be a 2D array (rows = y)");
             return std::make_shared<AmclMap>(static_cast<int>(data.shape(1)), static_cast<int>(data.shape(0)),
                                              resolution, origin,
                                              std::vector<int8_t>(data.data(), data.data() + data.size()));
           }),
           py::arg("data"), py::arg("resolution"), py::arg("origin"))
      .def("free_cell_count", [](const AmclMap& map) { return map.freeCells().size(); })
      .def("cast_range", &AmclMap::castRange, py::arg("x"), py::arg("y"), py::arg("angle"), py::arg("max_range"));

  py::class_<Amcl>(m, "_Amcl")
      .def(py::init<const AmclParams&, unsigned>(), py::arg("params"), py::arg("seed"))
      .def("set_map", &Amcl::setMap)
      .def("has_map", &Amcl::hasMap)
      .def("init_gaussian", &Amcl::initGaussian, py::arg("mean"), py::arg("cov"), py::arg("free_only") = false)
      .def("init_uniform", &Amcl::initUniform)
      .def("motion_update", &Amcl::motionUpdate, py::arg("odom_old"), py::arg("odom_new"),
           py::call_guard<py::gil_scoped_release>())
      .def(
          "sensor_update",
          [](Amcl& a, double angle_min, double angle_increment, double range_min, double range_max,
             const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges, const Eigen::Vector3d& laser_pose) {
            const LaserScan scan = toScan(angle_min, angle_increment, range_min, range_max, ranges);
            py::gil_scoped_release release;
            return a.sensorUpdate(scan, laser_pose);
          },
          py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"), py::arg("range_max"), py::arg("ranges"),
          py::arg("laser_pose"))
      .def("resample", &Amcl::resample, py::call_guard<py::gil_scoped_release>())
      .def("estimate",
           [](const Amcl& a) {
             const auto e = a.estimate();
             return py::make_tuple(Eigen::Vector3d(e.mean), Eigen::Matrix3d(e.covariance), e.cluster_weight, e.clusters);
           })
      .def("particles",
           [](const Amcl& a) {
             const auto& ps = a.particles();
             py::array_t<double> out({static_cast<py::ssize_t>(ps.size()), static_cast<py::ssize_t>(4)});
             auto o = out.mutable_unchecked<2>();
             for (std::size_t i = 0; i < ps.size(); ++i) {
               o(i, 0) = ps[i].pose.x();
               o(i, 1) = ps[i].pose.y();
               o(i, 2) = ps[i].pose.z();
               o(i, 3) = ps[i].weight;
             }
             return out;
           },
           "(N, 4) array: x, y, yaw, weight")
      .def_property_readonly("w_slow", &Amcl::wSlow)
      .def_property_readonly("last_average_weight", &Amcl::lastAverageWeight)
      .def_property_readonly("last_scan_fit", &Amcl::lastScanFit)
      .def_property_readonly("w_fast", &Amcl::wFast)
      .def("resample_limit", &Amcl::resampleLimit);

  m.def(
      "_load_map_image",
      [](const std::string& path, double occupied_thresh, double free_thresh, bool negate, const std::string& mode) {
        mbot::core::MapImageParams p;
        p.occupied_thresh = occupied_thresh;
        p.free_thresh = free_thresh;
        p.negate = negate;
        if (mode == "trinary") p.mode = mbot::core::MapMode::kTrinary;
        else if (mode == "scale") p.mode = mbot::core::MapMode::kScale;
        else if (mode == "raw") p.mode = mbot::core::MapMode::kRaw;
        else throw std::invalid_argument("mode must be trinary, scale or raw, not \"" + mode + "\"");
        const auto img = mbot::core::loadMapImage(path, p);
        py::array_t<int8_t> out({img.height, img.width});
        std::copy(img.data.begin(), img.data.end(), out.mutable_data());
        return out;
      },
      py::arg("path"), py::arg("occupied_thresh"), py::arg("free_thresh"), py::arg("negate"), py::arg("mode"),
      "map_server's pixel rules: (height, width) int8 occupancy, row 0 = the image's bottom row");

  py::class_<LogOddsModel>(m, "_LogOddsModel")
      .def(py::init<>())
      .def_static("from_probabilities", &LogOddsModel::fromProbabilities, py::arg("p_hit"), py::arg("p_miss"))
      .def_readwrite("hit", &LogOddsModel::hit)
      .def_readwrite("miss", &LogOddsModel::miss)
      .def_readwrite("min", &LogOddsModel::min)
      .def_readwrite("max", &LogOddsModel::max);

  py::class_<OccupancyGrid>(m, "_OccupancyGrid")
      .def(py::init<int, int, double, const Eigen::Vector2d&, const LogOddsModel&>(), py::arg("width"),
           py::arg("height"), py::arg("resolution"), py::arg("origin"), py::arg("model") = LogOddsModel())
      .def_property_readonly("width", &OccupancyGrid::width)
      .def_property_readonly("height", &OccupancyGrid::height)
      .def_property_readonly("resolution", &OccupancyGrid::resolution)
      .def_property_readonly("origin", &OccupancyGrid::origin)
      .def("contains", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.contains(toCell(c)); })
      .def("world_to_cell",
           [](const OccupancyGrid& g, const Eigen::Vector2d& p) {
             const Cell c = g.worldToCell(p);
             return std::make_pair(c.x, c.y);
           })
      .def("cell_center", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.cellCenter(toCell(c)); })
      .def("log_odds", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.logOdds(toCell(c)); })
      .def("probability", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.probability(toCell(c)); })
      .def("observed", [](const OccupancyGrid& g, std::pair<int, int> c) { return g.observed(toCell(c)); })
      .def("set_log_odds", [](OccupancyGrid& g, std::pair<int, int> c, float l) { g.setLogOdds(toCell(c), l); })
      .def("integrate_beam", &OccupancyGrid::integrateBeam, py::arg("start"), py::arg("end"), py::arg("hit"))
      .def(
          "integrate_scan",
          [](OccupancyGrid& g, const Eigen::Vector3d& pose, double angle_min, double angle_increment,
             double range_min, double range_max, const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges,
             double usable_range) {
            return g.integrateScan(pose, toScan(angle_min, angle_increment, range_min, range_max, ranges), usable_range);
          },
          py::arg("pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"),
          py::arg("range_max"), py::arg("ranges"), py::arg("usable_range"))
      .def("grow_to_include", &OccupancyGrid::growToInclude, py::arg("point"), py::arg("margin"))
      .def("observed_count", &OccupancyGrid::observedCount)
      .def("ros_data", [](const OccupancyGrid& g) {
        const std::vector<int8_t> data = g.toRosData();
        py::array_t<int8_t> out({g.height(), g.width()});
        std::copy(data.begin(), data.end(), out.mutable_data());
        return out;
      });

  m.def(
      "_bresenham_line",
      [](std::pair<int, int> a, std::pair<int, int> b) {
        std::vector<std::pair<int, int>> out;
        for (const Cell& c : mbot::core::bresenhamLine(toCell(a), toCell(b))) out.emplace_back(c.x, c.y);
        return out;
      },
      py::arg("start"), py::arg("end"));

  m.def(
      "_cast_rays",
      [](const OccupancyGrid& g, const Eigen::Vector2d& origin,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& angles, double max_range,
         double occupied_probability) {
        py::array_t<double> out(angles.size());
        double* o = out.mutable_data();
        const double* a = angles.data();
        {
          py::gil_scoped_release release;  // pure C++ loop: let other Python threads run
          for (py::ssize_t i = 0; i < angles.size(); ++i) {
            o[i] = mbot::core::castRay(g, origin, a[i], max_range, occupied_probability);
          }
        }
        return out;
      },
      py::arg("grid"), py::arg("origin"), py::arg("angles"), py::arg("max_range"),
      py::arg("occupied_probability") = 0.5);

  m.def("_point_polygon_distance", &mbot::core::pointPolygonDistance, py::arg("point"), py::arg("polygon"),
        "Distance [m] from a point to a solid polygon (0 inside).");

  py::class_<World2D>(m, "_World2D")
      .def(py::init<double>(), py::arg("bucket_size") = 0.5)
      .def("add_box", &World2D::addBox, py::arg("center"), py::arg("yaw"), py::arg("size_x"), py::arg("size_y"))
      .def("add_polygon", &World2D::addPolygon, py::arg("polygon"))
      .def("add_cylinder", &World2D::addCylinder, py::arg("center"), py::arg("radius"))
      .def("add_segment", &World2D::addSegment, py::arg("a"), py::arg("b"))
      .def("set_dynamic_polygons", &World2D::setDynamicPolygons, py::arg("polygons"))
      .def("set_dynamic_circles", &World2D::setDynamicCircles, py::arg("circles"))
      .def("distance_to_dynamic_polygons", &World2D::distanceToDynamicPolygons, py::arg("point"))
      .def("cast_ray", &World2D::castRay, py::arg("origin"), py::arg("angle"), py::arg("max_range"),
           py::arg("skip_dynamic") = -1)
      .def("overlaps", &World2D::overlaps, py::arg("polygon"), py::arg("skip_dynamic") = -1)
      .def_property_readonly("segment_count", &World2D::segmentCount)
      .def_property_readonly("circle_count", &World2D::circleCount);

  // A laser: owns its random generator so that a seeded simulation repeats exactly.
  struct LaserRng {
    std::mt19937 rng;
  };
  py::class_<LaserRng>(m, "_Rng").def(py::init([](unsigned seed) { return LaserRng{std::mt19937(seed)}; }));
  m.def(
      "_cast_scan",
      [](const World2D& world, const Eigen::Vector3d& pose, double angle_min, double angle_increment, int beams,
         double range_min, double range_max, double noise, double range_resolution, LaserRng& rng, int skip_dynamic) {
        py::array_t<float> out(beams);
        float* o = out.mutable_data();
        {
          py::gil_scoped_release release;
          world.castScan(pose, angle_min, angle_increment, beams, range_min, range_max, noise, range_resolution,
                         rng.rng, o, skip_dynamic);
        }
        return out;
      },
      py::arg("world"), py::arg("pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("beams"),
      py::arg("range_min"), py::arg("range_max"), py::arg("noise_stddev"), py::arg("range_resolution"),
      py::arg("rng"), py::arg("skip_dynamic") = -1);

  py::class_<DiffDriveParams>(m, "_DiffDriveParams")
      .def(py::init<>())
      .def_readwrite("wheel_separation", &DiffDriveParams::wheel_separation_m)
      .def_readwrite("wheel_diameter", &DiffDriveParams::wheel_diameter_m)
      .def_readwrite("wheel_acceleration", &DiffDriveParams::wheel_acceleration_mps2)
      .def_readwrite("cmd_timeout", &DiffDriveParams::cmd_timeout_s)
      .def_readwrite("slip_stddev", &DiffDriveParams::slip_stddev)
      .def_readwrite("odometry_from_world", &DiffDriveParams::odometry_from_world)
      .def("validate", &DiffDriveParams::validate);

  py::class_<DiffDrive>(m, "_DiffDrive")
      .def(py::init<const DiffDriveParams&, const Polygon&, const Eigen::Vector3d&, unsigned>(), py::arg("params"),
           py::arg("footprint"), py::arg("spawn_pose"), py::arg("seed"))
      .def("command", &DiffDrive::command, py::arg("v"), py::arg("w"), py::arg("now"))
      .def("step", &DiffDrive::step, py::arg("dt"), py::arg("now"), py::arg("world"), py::arg("self_index") = -1)
      .def("set_pose", &DiffDrive::setPose)
      .def("reset_odometry", &DiffDrive::resetOdometry)
      .def_property_readonly("pose", &DiffDrive::pose)
      .def_property_readonly("odom_pose", &DiffDrive::odomPose)
      .def_property_readonly("linear_velocity", &DiffDrive::linearVelocity)
      .def_property_readonly("angular_velocity", &DiffDrive::angularVelocity)
      .def_property_readonly("wheel_angles", &DiffDrive::wheelAngles)
      .def("footprint_in_world", &DiffDrive::footprintInWorld);

  // --- SLAM (offline tools and tests; the node is roscpp) --------------------------------------
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
           });

  // --- Costmaps ----------------------------------------------------------------------------------
  m.def(
      "_inflate",
      [](py::array_t<uint8_t, py::array::c_style> costs, double resolution, double inscribed_radius,
         double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
        if (costs.ndim() != 2) throw std::invalid_argument("costs must be a 2D array (rows = y)");
        mbot::core::Costmap map(static_cast<int>(costs.shape(1)), static_cast<int>(costs.shape(0)), resolution, {0, 0});
        std::copy(costs.data(), costs.data() + costs.size(), map.costs().begin());
        mbot::core::InflationParams p;
        p.inscribed_radius = inscribed_radius;
        p.inflation_radius = inflation_radius;
        p.cost_scaling_factor = cost_scaling_factor;
        p.inflate_unknown = inflate_unknown;
        {
          py::gil_scoped_release release;
          mbot::core::inflate(map, p);
        }
        std::copy(map.costs().begin(), map.costs().end(), costs.mutable_data());
      },
      py::arg("costs"), py::arg("resolution"), py::arg("inscribed_radius"), py::arg("inflation_radius"),
      py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false);

  using mbot::core::Costmap;
  py::class_<Costmap>(m, "_Costmap")
      .def(py::init([](const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& costs, double resolution,
                       const Eigen::Vector2d& origin) {
             if (costs.ndim() != 2) throw std::invalid_argument("costs must be a 2D array (rows = y)");
             auto map = std::make_unique<Costmap>(static_cast<int>(costs.shape(1)), static_cast<int>(costs.shape(0)),
                                                  resolution, origin);
             std::copy(costs.data(), costs.data() + costs.size(), map->costs().begin());
             return map;
           }),
           py::arg("costs"), py::arg("resolution"), py::arg("origin"))
      .def_property_readonly("width", &Costmap::width)
      .def_property_readonly("height", &Costmap::height)
      .def_property_readonly("resolution", &Costmap::resolution)
      .def_property_readonly("origin", [](const Costmap& c) { return Eigen::Vector2d(c.origin()); })
      .def("costs", [](const Costmap& c) {
        py::array_t<uint8_t> out({c.height(), c.width()});
        std::copy(c.costs().begin(), c.costs().end(), out.mutable_data());
        return out;
      })
      .def("set_costs",
           [](Costmap& c, const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& costs) {
             if (costs.ndim() != 2 || costs.shape(0) != c.height() || costs.shape(1) != c.width()) {
               throw std::invalid_argument("set_costs: the array must be height x width = " + std::to_string(c.height()) +
                                           " x " + std::to_string(c.width()));
             }
             std::copy(costs.data(), costs.data() + costs.size(), c.costs().begin());
           })
      .def("move_origin", &Costmap::moveOrigin, py::arg("new_origin"), py::arg("fill"))
      .def(
          "inflate",
          [](Costmap& c, double inscribed_radius, double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
            mbot::core::InflationParams p{inscribed_radius, inflation_radius, cost_scaling_factor, inflate_unknown};
            py::gil_scoped_release release;
            mbot::core::inflate(c, p);
          },
          "Inflates this costmap in place (no copies: as a node does).", py::arg("inscribed_radius"),
          py::arg("inflation_radius"), py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false)
      .def(
          "inflate_window",
          [](Costmap& c, const Costmap& base, int x0, int y0, int x1, int y1, double inscribed_radius,
             double inflation_radius, double cost_scaling_factor, bool inflate_unknown) {
            mbot::core::InflationParams p{inscribed_radius, inflation_radius, cost_scaling_factor, inflate_unknown};
            py::gil_scoped_release release;
            mbot::core::inflateWindow(base, c, {x0, y0, x1, y1}, p);
          },
          "Cells [x0, x1) x [y0, y1) become base's, inflated (bounded update).", py::arg("base"), py::arg("x0"),
          py::arg("y0"), py::arg("x1"), py::arg("y1"), py::arg("inscribed_radius"), py::arg("inflation_radius"),
          py::arg("cost_scaling_factor"), py::arg("inflate_unknown") = false)
      .def(
          "update_with_scan",
          [](Costmap& c, const Eigen::Vector3d& sensor_pose, double angle_min, double angle_increment, double range_min,
             double range_max, const py::array_t<float, py::array::c_style | py::array::forcecast>& ranges,
             double obstacle_range, double raytrace_range, bool marking, bool clearing, bool inf_is_valid,
             bool too_close_is_obstacle) {
            mbot::core::ObservationSourceParams p;
            p.obstacle_range = obstacle_range;
            p.raytrace_range = raytrace_range;
            p.marking = marking;
            p.clearing = clearing;
            p.inf_is_valid = inf_is_valid;
            p.too_close_is_obstacle = too_close_is_obstacle;
            const LaserScan scan = toScan(angle_min, angle_increment, range_min, range_max, ranges);
            py::gil_scoped_release release;
            return mbot::core::updateWithScan(c, sensor_pose, scan, p);
          },
          py::arg("sensor_pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_min"),
          py::arg("range_max"), py::arg("ranges"), py::arg("obstacle_range"), py::arg("raytrace_range"),
          py::arg("marking") = true, py::arg("clearing") = true, py::arg("inf_is_valid") = true,
          py::arg("too_close_is_obstacle") = true)
      .def(
          "footprint_cost",
          [](const Costmap& c, const Eigen::Vector3d& pose, const std::vector<Eigen::Vector2d>& footprint,
             bool unknown_is_obstacle) { return mbot::core::footprintCost(c, pose, footprint, unknown_is_obstacle); },
          py::arg("pose"), py::arg("footprint"), py::arg("unknown_is_obstacle") = true)
      .def(
          "footprint_cells",
          [](const Costmap& c, const Eigen::Vector3d& pose, const std::vector<Eigen::Vector2d>& footprint) {
            std::vector<std::pair<int, int>> out;
            for (const auto& cell : mbot::core::footprintCells(c, pose, footprint)) out.emplace_back(cell.x, cell.y);
            return out;
          },
          py::arg("pose"), py::arg("footprint"))
      .def("occupancy_data", [](const Costmap& c) {
        const auto d = c.toOccupancyData();
        py::array_t<int8_t> out({c.height(), c.width()});
        std::copy(d.begin(), d.end(), out.mutable_data());
        return out;
      });
  using mbot::core::GlobalPlanner;
  py::class_<GlobalPlanner>(m, "_GlobalPlanner")
      .def(py::init([](bool use_astar, bool allow_unknown, double default_tolerance, bool use_bounds) {
             mbot::core::PlannerParams p;
             p.use_astar = use_astar;
             p.allow_unknown = allow_unknown;
             p.default_tolerance = default_tolerance;
             p.use_bounds = use_bounds;
             return std::make_unique<GlobalPlanner>(p);
           }),
           py::arg("use_astar") = false, py::arg("allow_unknown") = true, py::arg("default_tolerance") = 0.0,
           py::arg("use_bounds") = true)
      .def(
          "make_plan",
          [](GlobalPlanner& planner, const Costmap& map, const Eigen::Vector2d& start, const Eigen::Vector2d& goal) {
            mbot::core::Plan plan;
            {
              py::gil_scoped_release release;
              plan = planner.makePlan(map, start, goal);
            }
            py::array_t<double> path({static_cast<py::ssize_t>(plan.path.size()), static_cast<py::ssize_t>(2)});
            auto out = path.mutable_unchecked<2>();
            for (std::size_t i = 0; i < plan.path.size(); ++i) {
              out(i, 0) = plan.path[i].x();
              out(i, 1) = plan.path[i].y();
            }
            return py::make_tuple(std::string(mbot::core::toString(plan.status)), path, plan.message, plan.expanded,
                                  plan.coarse_blocks);
          },
          py::arg("costmap"), py::arg("start"), py::arg("goal"))
      .def(
          "potential",
          [](const GlobalPlanner& planner, const Costmap& map) {
            py::array_t<float> out({map.height(), map.width()});
            float* d = out.mutable_data();
            for (std::size_t i = 0; i < map.costs().size(); ++i) d[i] = planner.valueAt(i);
            return out;
          },
          py::arg("costmap"));

  // --- Footprints and the local planner ----------------------------------------------------------
  m.def("_circle_footprint", &mbot::core::circleFootprint, py::arg("radius"));
  m.def("_pad_footprint", &mbot::core::padFootprint, py::arg("footprint"), py::arg("padding"));
  m.def("_inscribed_radius", &mbot::core::inscribedRadius, py::arg("footprint"));
  m.def(
      "_path_lengths",
      [](py::array_t<uint8_t, py::array::c_style | py::array::forcecast> passable, int col, int row) {
        if (passable.ndim() != 2) throw std::invalid_argument("_path_lengths: passable must be a 2D array");
        const int h = static_cast<int>(passable.shape(0)), w = static_cast<int>(passable.shape(1));
        std::vector<uint8_t> cells(passable.data(), passable.data() + passable.size());
        std::vector<float> d;
        {
          py::gil_scoped_release release;
          d = mbot::core::pathLengths(cells, w, h, mbot::core::Cell{col, row});
        }
        py::array_t<float> out({h, w});
        std::copy(d.begin(), d.end(), out.mutable_data());
        return out;
      },
      py::arg("passable"), py::arg("col"), py::arg("row"));
  m.def(
      "_shortest_paths_through_all",
      [](py::array_t<double, py::array::c_style | py::array::forcecast> d, int exact_max) {
        if (d.ndim() != 2 || d.shape(0) != d.shape(1)) {
          throw std::invalid_argument("_shortest_paths_through_all: d must be an n x n array");
        }
        const int n = static_cast<int>(d.shape(0));
        std::vector<double> m(d.data(), d.data() + d.size());
        std::vector<double> rest;
        {
          py::gil_scoped_release release;
          rest = mbot::core::shortestPathsThroughAll(m, n, exact_max);
        }
        return py::array_t<double>(n, rest.data());
      },
      py::arg("d"), py::arg("exact_max") = 12);
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
