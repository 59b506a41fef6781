#include "ros_conversions.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

namespace mbot {
namespace ros_glue {

core::LaserScan fromRos(const sensor_msgs::LaserScan& msg) {
  core::LaserScan scan;
  scan.angle_min_rad = msg.angle_min;
  scan.angle_increment_rad = msg.angle_increment;
  scan.range_min_m = msg.range_min;
  scan.range_max_m = msg.range_max;
  scan.ranges_m = msg.ranges;
  return scan;
}

namespace {
void fillInfo(int width, int height, double resolution, const Eigen::Vector2d& origin, nav_msgs::MapMetaData& info) {
  info.resolution = static_cast<float>(resolution);
  info.width = width;
  info.height = height;
  info.origin.position.x = origin.x();
  info.origin.position.y = origin.y();
  info.origin.position.z = 0.0;
  info.origin.orientation.w = 1.0;
}
}  // namespace

void toRos(const core::OccupancyGrid& grid, nav_msgs::OccupancyGrid& out) {
  fillInfo(grid.width(), grid.height(), grid.resolution(), grid.origin(), out.info);
  const std::vector<int8_t> data = grid.toRosData();
  out.data.assign(data.begin(), data.end());
}

void toRos(core::OccupancyImage&& image, nav_msgs::OccupancyGrid& out) {
  fillInfo(image.width, image.height, image.resolution, image.origin, out.info);
  out.data = std::move(image.data);  // both std::vector<int8_t>: no copy
}

std::string describeScanProblem(const sensor_msgs::LaserScan& msg) {
  std::ostringstream why;
  if (msg.ranges.empty()) {
    why << "it has no beams";
  } else if (!std::isfinite(msg.angle_min) || !std::isfinite(msg.angle_increment) || msg.angle_increment == 0.0f) {
    why << "its angle_min/angle_increment (" << msg.angle_min << ", " << msg.angle_increment << ") are not usable";
  } else if (!std::isfinite(msg.range_max) || !(msg.range_max > msg.range_min)) {
    why << "its range_max (" << msg.range_max << ") is not above range_min (" << msg.range_min << ")";
  } else if (std::isfinite(msg.angle_max)) {
    const double announced = (msg.angle_max - msg.angle_min) / msg.angle_increment + 1.0;
    if (std::abs(announced - static_cast<double>(msg.ranges.size())) > 1.5) {
      why << "angle_min..angle_max announce " << std::lround(announced) << " beams but it has " << msg.ranges.size();
    }
  }
  if (why.str().empty()) {
    bool any = false;
    for (float r : msg.ranges) any = any || (!std::isnan(r) && r >= msg.range_min);
    if (!any) why << "none of its " << msg.ranges.size() << " ranges is usable (all NaN or below range_min)";
  }
  return why.str();
}

core::ParamValue fromXmlRpc(XmlRpc::XmlRpcValue& v) {
  using core::ParamValue;
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return ParamValue::ofBool(static_cast<bool>(v));
    case XmlRpc::XmlRpcValue::TypeInt: return ParamValue::ofInt(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: return ParamValue::ofDouble(static_cast<double>(v));
    case XmlRpc::XmlRpcValue::TypeString: return ParamValue::ofString(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      std::vector<ParamValue> items;
      for (int i = 0; i < v.size(); ++i) items.push_back(fromXmlRpc(v[i]));
      return ParamValue::ofList(std::move(items));
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      std::map<std::string, ParamValue> fields;
      for (auto it = v.begin(); it != v.end(); ++it) fields[it->first] = fromXmlRpc(it->second);
      return ParamValue::ofMap(std::move(fields));
    }
    case XmlRpc::XmlRpcValue::TypeInvalid: return ParamValue();
    default: return ParamValue::ofString(v.toXml());
  }
}

std::pair<std::optional<double>, std::string> planarYaw(double x, double y, double z, double w, const std::string& what) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(w)) {
    return {std::nullopt, what + " has NaN or infinite components"};
  }
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  char buf[256];
  if (n < 1e-6) {
    std::snprintf(buf, sizeof buf, "%s is a zero quaternion (length %.3g); it has no heading", what.c_str(), n);
    return {std::nullopt, buf};
  }
  std::string warning;
  if (std::abs(n - 1.0) > 1e-3) {
    std::snprintf(buf, sizeof buf, "%s (%.3f, %.3f, %.3f, %.3f) has length %.3f; normalized", what.c_str(), x, y, z, w, n);
    warning = buf;
  }
  x /= n;
  y /= n;
  z /= n;
  w /= n;
  if (1.0 - 2.0 * (x * x + y * y) < 1.0 - 1e-3) {
    return {std::nullopt, what + " tilts the robot (its z axis must stay vertical for planar navigation)"};
  }
  return {std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)), warning};
}

}  // namespace ros_glue
}  // namespace mbot
