// Bindings of amcl's particle filter, and map_server's pixel rules for map images.
#include "bindings.h"

#include <tuple>

#include "mbot_slam_navigation/core/amcl.h"
#include "mbot_slam_navigation/core/map_image.h"

namespace mbot {
namespace bindings {

using namespace mbot::core;

void bindAmcl(py::module& m) {
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
}

}  // namespace bindings
}  // namespace mbot
