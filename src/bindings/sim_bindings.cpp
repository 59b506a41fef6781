// Bindings of the simulator's world (shapes, lasers) and its differential drive.
#include "bindings.h"

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "mbot_slam_navigation/core/diff_drive.h"
#include "mbot_slam_navigation/core/world2d.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindSimulation(py::module& m) {
  m.def("_point_polygon_distance", &mbot::core::pointPolygonDistance, py::arg("point"), py::arg("polygon"),
        "Distance [m] from a point to a solid polygon (0 inside).");

  const double inf = std::numeric_limits<double>::infinity();
  const auto range = [](double lo, double hi) { return HeightRange{lo, hi}; };
  py::class_<World2D>(m, "_World2D")
      .def(py::init<double>(), py::arg("bucket_size") = 0.5)
      .def(
          "add_box",
          [range](World2D& w, const Eigen::Vector2d& c, double yaw, double sx, double sy, double z_lo, double z_hi) {
            w.addBox(c, yaw, sx, sy, range(z_lo, z_hi));
          },
          py::arg("center"), py::arg("yaw"), py::arg("size_x"), py::arg("size_y"), py::arg("z_lo") = -inf,
          py::arg("z_hi") = inf)
      .def(
          "add_polygon", [range](World2D& w, const Polygon& p, double z_lo, double z_hi) { w.addPolygon(p, range(z_lo, z_hi)); },
          py::arg("polygon"), py::arg("z_lo") = -inf, py::arg("z_hi") = inf)
      .def(
          "add_cylinder",
          [range](World2D& w, const Eigen::Vector2d& c, double r, double z_lo, double z_hi) {
            w.addCylinder(c, r, range(z_lo, z_hi));
          },
          py::arg("center"), py::arg("radius"), py::arg("z_lo") = -inf, py::arg("z_hi") = inf)
      .def(
          "add_segment",
          [range](World2D& w, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double z_lo, double z_hi) {
            w.addSegment(a, b, range(z_lo, z_hi));
          },
          py::arg("a"), py::arg("b"), py::arg("z_lo") = -inf, py::arg("z_hi") = inf)
      .def(
          "add_grid",
          [range](World2D& w, py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast> cells,
                  const Eigen::Vector2d& origin, double yaw, double resolution, double z_lo, double z_hi) {
            if (cells.ndim() != 2) throw std::invalid_argument("add_grid: cells must be a 2-D array (rows, cols)");
            GridShape g;
            g.origin = origin;
            g.yaw = yaw;
            g.resolution = resolution;
            g.height = static_cast<int>(cells.shape(0));
            g.width = static_cast<int>(cells.shape(1));
            g.cells.assign(cells.data(), cells.data() + cells.size());
            g.heights = range(z_lo, z_hi);
            w.addGrid(std::move(g));
          },
          py::arg("cells"), py::arg("origin"), py::arg("yaw"), py::arg("resolution"), py::arg("z_lo") = -inf,
          py::arg("z_hi") = inf,
          "An occupancy raster: cells[row, col] != 0 solid; row r, column c covers [c, c+1) x [r, r+1) x "
          "resolution along the raster's axes from `origin` (world, m), rotated by yaw.")
      .def("set_dynamic_polygons", &World2D::setDynamicPolygons, py::arg("polygons"))
      .def("set_dynamic_circles", &World2D::setDynamicCircles, py::arg("circles"))
      .def("distance_to_dynamic_polygons", &World2D::distanceToDynamicPolygons, py::arg("point"))
      .def("cast_ray", &World2D::castRay, py::arg("origin"), py::arg("angle"), py::arg("max_range"),
           py::arg("skip_dynamic") = -1, py::arg("plane_z") = std::numeric_limits<double>::quiet_NaN())
      .def(
          "overlaps",
          [range](const World2D& w, const Polygon& p, int skip, double z_lo, double z_hi) {
            return w.overlaps(p, skip, range(z_lo, z_hi));
          },
          py::arg("polygon"), py::arg("skip_dynamic") = -1, py::arg("z_lo") = -inf, py::arg("z_hi") = inf)
      .def_property_readonly("grid_count", &World2D::gridCount)
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
         double range_min, double range_max, double noise, double range_resolution, LaserRng& rng, int skip_dynamic,
         double plane_z) {
        py::array_t<float> out(beams);
        float* o = out.mutable_data();
        {
          py::gil_scoped_release release;
          world.castScan(pose, angle_min, angle_increment, beams, range_min, range_max, noise, range_resolution,
                         rng.rng, o, skip_dynamic, plane_z);
        }
        return out;
      },
      py::arg("world"), py::arg("pose"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("beams"),
      py::arg("range_min"), py::arg("range_max"), py::arg("noise_stddev"), py::arg("range_resolution"),
      py::arg("rng"), py::arg("skip_dynamic") = -1, py::arg("plane_z") = std::numeric_limits<double>::quiet_NaN());

  py::class_<DiffDriveParams>(m, "_DiffDriveParams")
      .def(py::init<>())
      .def_readwrite("wheel_separation", &DiffDriveParams::wheel_separation_m)
      .def_readwrite("wheel_diameter", &DiffDriveParams::wheel_diameter_m)
      .def_readwrite("wheel_acceleration", &DiffDriveParams::wheel_acceleration_mps2)
      .def_readwrite("cmd_timeout", &DiffDriveParams::cmd_timeout_s)
      .def_readwrite("slip_stddev", &DiffDriveParams::slip_stddev)
      .def_readwrite("odometry_from_world", &DiffDriveParams::odometry_from_world)
      .def(
          "set_body_heights", [](DiffDriveParams& p, double lo, double hi) { p.body = HeightRange{lo, hi}; },
          py::arg("z_lo"), py::arg("z_hi"), "[m above the floor] the heights the body spans")
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
}

}  // namespace bindings
}  // namespace mbot
