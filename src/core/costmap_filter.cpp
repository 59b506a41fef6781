#include "mbot_slam_navigation/core/costmap_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "mbot_slam_navigation/core/costmap.h"

namespace mbot {
namespace core {

uint8_t keepoutCost(int8_t value) {
  if (value <= 0) return cost::kFree;
  if (value >= 100) return cost::kLethal;
  return static_cast<uint8_t>(1 + (251 * (value - 1)) / 98);  // 1..99 -> 1..252
}

int FilterMask::column(double x) const { return static_cast<int>(std::floor((x - origin_.x()) / resolution_)); }
int FilterMask::row(double y) const { return static_cast<int>(std::floor((y - origin_.y()) / resolution_)); }

int8_t FilterMask::valueAt(const Eigen::Vector2d& p) const {
  if (!valid()) return -1;
  const int c = column(p.x()), r = row(p.y());
  if (c < 0 || r < 0 || c >= width_ || r >= height_) return -1;
  return data_[static_cast<std::size_t>(r) * width_ + c];
}

int FilterMask::zoneAt(const Eigen::Vector2d& p) const {
  if (!valid()) return -1;
  const int c = column(p.x()), r = row(p.y());
  if (c < 0 || r < 0 || c >= width_ || r >= height_) return -1;
  return labels_[static_cast<std::size_t>(r) * width_ + c];
}

void FilterMask::set(const std::vector<int8_t>& data, int width, int height, const Eigen::Vector2d& origin,
                     double resolution) {
  if (width <= 0 || height <= 0 || data.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument(std::to_string(data.size()) + " cells for " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (!(resolution > 0.0) || !origin.allFinite()) throw std::invalid_argument("the resolution or origin is not usable");
  width_ = width;
  height_ = height;
  origin_ = origin;
  resolution_ = resolution;
  data_ = data;
  labelZones({});
  findRuns();
}

void FilterMask::findRuns() {
  runs_.assign(height_, {});
  for (int r = 0; r < height_; ++r) {
    const int8_t* row = data_.data() + static_cast<std::size_t>(r) * width_;
    for (int c = 0; c < width_;) {
      if (row[c] <= 0) {
        ++c;
        continue;
      }
      const int begin = c;
      while (c < width_ && row[c] > 0) ++c;
      runs_[r].emplace_back(begin, c);
    }
  }
}

void FilterMask::setPolygons(const std::vector<ZonePolygon>& zones, double resolution) {
  if (zones.empty()) throw std::invalid_argument("no polygons");
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  for (const auto& z : zones) {
    if (z.points.size() < 3) {
      throw std::invalid_argument(z.name + ": a polygon needs at least 3 points, it has " + std::to_string(z.points.size()));
    }
    for (const auto& p : z.points) {
      if (!p.allFinite()) throw std::invalid_argument(z.name + ": a point is not finite");
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  resolution_ = resolution;
  origin_ = (lo / resolution).array().floor().matrix() * resolution - Eigen::Vector2d::Constant(resolution);
  width_ = static_cast<int>(std::ceil((hi.x() - origin_.x()) / resolution)) + 2;
  height_ = static_cast<int>(std::ceil((hi.y() - origin_.y()) / resolution)) + 2;
  cv::Mat label(height_, width_, CV_32S, cv::Scalar(0));
  for (std::size_t i = 0; i < zones.size(); ++i) {
    std::vector<cv::Point> pts;
    for (const auto& p : zones[i].points) {
      pts.emplace_back(static_cast<int>(std::floor((p.x() - origin_.x()) / resolution)),
                       static_cast<int>(std::floor((p.y() - origin_.y()) / resolution)));
    }
    // Outline and interior: every cell the polygon touches (as costmap_prohibition_layer fills).
    cv::fillPoly(label, std::vector<std::vector<cv::Point>>{pts}, cv::Scalar(static_cast<int>(i) + 1), cv::LINE_8);
    cv::polylines(label, std::vector<std::vector<cv::Point>>{pts}, true, cv::Scalar(static_cast<int>(i) + 1), 1, cv::LINE_8);
  }
  data_.assign(static_cast<std::size_t>(width_) * height_, 0);
  labels_.assign(data_.size(), -1);
  zone_names_.clear();
  for (const auto& z : zones) zone_names_.push_back(z.name);
  for (int r = 0; r < height_; ++r) {
    const int* row_ptr = label.ptr<int>(r);
    for (int c = 0; c < width_; ++c) {
      if (row_ptr[c] == 0) continue;
      const std::size_t i = static_cast<std::size_t>(r) * width_ + c;
      data_[i] = 100;
      labels_[i] = row_ptr[c] - 1;
    }
  }
  findRuns();
}

void FilterMask::labelZones(const std::vector<std::string>& names) {
  cv::Mat on(height_, width_, CV_8U);
  for (int r = 0; r < height_; ++r) {
    uint8_t* p = on.ptr<uint8_t>(r);
    for (int c = 0; c < width_; ++c) p[c] = data_[static_cast<std::size_t>(r) * width_ + c] > 0 ? 1 : 0;
  }
  cv::Mat label, stats, centroids;
  const int n = cv::connectedComponentsWithStats(on, label, stats, centroids, 8, CV_32S);
  labels_.assign(data_.size(), -1);
  for (int r = 0; r < height_; ++r) {
    const int* p = label.ptr<int>(r);
    for (int c = 0; c < width_; ++c) labels_[static_cast<std::size_t>(r) * width_ + c] = p[c] - 1;  // 0 is the background
  }
  zone_names_.clear();
  for (int k = 1; k < n; ++k) {
    if (static_cast<std::size_t>(k - 1) < names.size()) {
      zone_names_.push_back(names[k - 1]);
      continue;
    }
    char buf[96];
    std::snprintf(buf, sizeof buf, "#%d at (%.1f, %.1f)", k, origin_.x() + (centroids.at<double>(k, 0) + 0.5) * resolution_,
                  origin_.y() + (centroids.at<double>(k, 1) + 0.5) * resolution_);
    zone_names_.push_back(buf);
  }
}

}  // namespace core
}  // namespace mbot
