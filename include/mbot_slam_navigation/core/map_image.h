// map_server's image rules: a greyscale or colour image (PGM, PNG, ... as OpenCV reads them) to
// nav_msgs/OccupancyGrid values. (Saving, the other way, is maps/map_io.py's occupancy_to_image.)
//
// Loading, per pixel: the mean of the colour channels (the alpha channel excluded), inverted when
// `negate`; occ = (255 - mean) / 255. Then, as ROS's map_server:
//   trinary: occ > occupied_thresh -> 100, occ < free_thresh -> 0, otherwise -1;
//   scale:   the same, but between the thresholds 99 (occ - free) / (occupied - free), truncated, or
//            -1 where the pixel is fully transparent (alpha 0);
//   raw:     the mean itself, 0..255 stored as int8 (255 reads as -1).
// Deliberate differences from ROS: the alpha channel is never averaged into the colour (ROS does so
// in trinary mode), and a 3-channel image has no alpha (ROS reads its blue channel as alpha).
// 16-bit images are scaled to 8 bits. The image's top row becomes the map's highest row (data row
// height-1), as the map's cell (0, 0) is its lower-left corner.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace mbot {
namespace core {

enum class MapMode { kTrinary, kScale, kRaw };

struct MapImageParams {
  double occupied_thresh = 0.65;  ///< in [0, 1], > free_thresh
  double free_thresh = 0.196;     ///< in [0, 1]
  bool negate = false;
  MapMode mode = MapMode::kTrinary;
};

struct MapImageData {
  int width = 0;
  int height = 0;
  std::vector<int8_t> data;  ///< row-major, row 0 = the image's bottom row
};

/// Converts an 8-bit or 16-bit image with 1, 2 (grey + alpha), 3 (BGR) or 4 (BGRA) channels.
/// Throws std::invalid_argument for an empty image, another depth or channel count, or thresholds
/// that are not 0 <= free_thresh < occupied_thresh <= 1.
MapImageData imageToOccupancy(const cv::Mat& image, const MapImageParams& params);

/// Reads `path` with OpenCV (alpha kept) and converts it. Throws std::runtime_error naming the file
/// when it cannot be read or decoded.
MapImageData loadMapImage(const std::string& path, const MapImageParams& params);

}  // namespace core
}  // namespace mbot
