#include "mbot_slam_navigation/core/map_image.h"

#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace mbot {
namespace core {

MapImageData imageToOccupancy(const cv::Mat& image, const MapImageParams& params) {
  if (image.empty()) throw std::invalid_argument("map image: the image is empty");
  if (!(params.free_thresh >= 0.0 && params.free_thresh < params.occupied_thresh && params.occupied_thresh <= 1.0)) {
    throw std::invalid_argument("map image: thresholds must satisfy 0 <= free_thresh (" + std::to_string(params.free_thresh) +
                                ") < occupied_thresh (" + std::to_string(params.occupied_thresh) + ") <= 1");
  }
  cv::Mat img8;
  if (image.depth() == CV_8U) {
    img8 = image;
  } else if (image.depth() == CV_16U) {
    image.convertTo(img8, CV_8U, 1.0 / 257.0);
  } else {
    throw std::invalid_argument("map image: only 8-bit and 16-bit images are supported");
  }
  const int channels = img8.channels();
  if (channels < 1 || channels > 4) throw std::invalid_argument("map image: unsupported channel count");
  const bool has_alpha = channels == 2 || channels == 4;
  const int colour_channels = has_alpha ? channels - 1 : channels;

  MapImageData out;
  out.width = img8.cols;
  out.height = img8.rows;
  out.data.assign(static_cast<std::size_t>(out.width) * out.height, -1);
  for (int row = 0; row < img8.rows; ++row) {
    const uint8_t* p = img8.ptr<uint8_t>(row);
    const std::size_t map_row = static_cast<std::size_t>(out.height - 1 - row);
    for (int col = 0; col < img8.cols; ++col, p += channels) {
      int sum = 0;
      for (int k = 0; k < colour_channels; ++k) sum += p[k];
      double mean = static_cast<double>(sum) / colour_channels;
      const int alpha = has_alpha ? p[channels - 1] : 255;
      if (params.negate) mean = 255.0 - mean;
      int8_t& value = out.data[map_row * out.width + col];
      if (params.mode == MapMode::kRaw) {
        value = static_cast<int8_t>(static_cast<uint8_t>(mean));
        continue;
      }
      const double occ = (255.0 - mean) / 255.0;
      if (occ > params.occupied_thresh) {
        value = 100;
      } else if (occ < params.free_thresh) {
        value = 0;
      } else if (params.mode == MapMode::kTrinary || alpha == 0) {
        value = -1;
      } else {
        const double ratio = (occ - params.free_thresh) / (params.occupied_thresh - params.free_thresh);
        value = static_cast<int8_t>(99.0 * ratio);
      }
    }
  }
  return out;
}

MapImageData loadMapImage(const std::string& path, const MapImageParams& params) {
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("failed to decode image file \"" + path + "\": " + e.what());
  }
  if (image.empty()) throw std::runtime_error("failed to open image file \"" + path + "\" (missing or not an image)");
  try {
    return imageToOccupancy(image, params);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("image file \"" + path + "\": " + e.what());
  }
}

}  // namespace core
}  // namespace mbot
