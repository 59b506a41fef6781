#include "mbot_slam_navigation/core/inflation_layer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace mbot {
namespace core {

void InflationParams::validate() const {
  if (!(inscribed_radius >= 0.0)) throw std::invalid_argument("inscribed radius must be >= 0");
  if (!(inflation_radius >= 0.0)) throw std::invalid_argument("inflation_radius must be >= 0");
  if (!(cost_scaling_factor >= 0.0)) throw std::invalid_argument("cost_scaling_factor must be >= 0");
}

uint8_t inflatedCost(double d, const InflationParams& p) {
  if (d <= 0.0) return cost::kLethal;
  if (d <= p.inscribed_radius) return cost::kInscribed;
  if (d > p.inflation_radius + 1e-9) return cost::kFree;  // a cell exactly at the radius is inflated
  return static_cast<uint8_t>((cost::kInscribed - 1) * std::exp(-p.cost_scaling_factor * (d - p.inscribed_radius)));
}

void inflate(Costmap& map, const InflationParams& params) {
  params.validate();
  const int w = map.width(), h = map.height();
  std::vector<uint8_t>& costs = map.costs();
  // distanceTransform measures to the nearest zero pixel: lethal cells are the zeros.
  cv::Mat not_lethal(h, w, CV_8UC1);
  bool any = false;
  for (int i = 0; i < w * h; ++i) {
    const bool lethal = costs[i] == cost::kLethal;
    not_lethal.data[i] = lethal ? 0 : 255;
    any = any || lethal;
  }
  if (!any) return;
  cv::Mat dist;
  cv::distanceTransform(not_lethal, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  // The exact transform measures integer offsets, so d^2 is an integer number of cells^2: a table
  // indexed by it holds every cost there is (costmap_2d caches costs by cell distance likewise).
  const double res = map.resolution();
  const int max_cells = static_cast<int>(std::ceil(params.inflation_radius / res)) + 1;
  std::vector<uint8_t> by_d2(max_cells * max_cells + 1);
  for (std::size_t d2 = 0; d2 < by_d2.size(); ++d2) by_d2[d2] = inflatedCost(std::sqrt(double(d2)) * res, params);
  const float* d = dist.ptr<float>(0);
  for (int i = 0; i < w * h; ++i) {
    const float cells = d[i];
    if (cells == 0.0f || cells >= max_cells) continue;
    const uint8_t c = by_d2[static_cast<std::size_t>(std::lround(cells * cells))];
    uint8_t& old = costs[i];
    if (old == cost::kNoInformation) {
      if (params.inflate_unknown ? c > cost::kFree : c >= cost::kInscribed) old = c;
    } else if (c > old) {
      old = c;
    }
  }
}

}  // namespace core
}  // namespace mbot
