// map_server's pixel rules (trinary, scale, raw, negate, alpha) and image loading errors.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "mbot_slam_navigation/core/map_image.h"

using mbot::core::imageToOccupancy;
using mbot::core::loadMapImage;
using mbot::core::MapImageParams;
using mbot::core::MapMode;

namespace {
// One row of grey pixels: black, dark grey (occ 0.75), mid grey (occ ~0.5), light (occ 0.1), white.
cv::Mat greyRow() { return (cv::Mat_<uint8_t>(1, 5) << 0, 64, 128, 230, 255); }
}  // namespace

TEST(MapImage, TrinaryThresholdsAreStrictAsMapServer) {
  const auto m = imageToOccupancy(greyRow(), MapImageParams{});
  EXPECT_EQ(m.width, 5);
  EXPECT_EQ(m.height, 1);
  const std::vector<int8_t> expected{100, 100, -1, 0, 0};
  EXPECT_EQ(m.data, expected);
  // occ exactly at the threshold is neither occupied nor free: 255 - 0.65 * 255 = 89.25 is not a
  // pixel value, so use a threshold that lands on one (pixel 51 -> occ 0.8).
  MapImageParams p;
  p.occupied_thresh = 0.8;
  const auto at = imageToOccupancy((cv::Mat_<uint8_t>(1, 1) << 51), p);
  EXPECT_EQ(at.data[0], -1);
}

TEST(MapImage, NegateSwapsBlackAndWhite) {
  MapImageParams p;
  p.negate = true;
  const auto m = imageToOccupancy(greyRow(), p);
  // 64 inverted is 191: occ 0.25, between the thresholds.
  const std::vector<int8_t> expected{0, -1, -1, 100, 100};
  EXPECT_EQ(m.data, expected);
}

TEST(MapImage, ScaleModeGivesGradedValuesBetweenTheThresholds) {
  MapImageParams p;
  p.mode = MapMode::kScale;
  const auto m = imageToOccupancy(greyRow(), p);
  EXPECT_EQ(m.data[0], 100);
  EXPECT_EQ(m.data[4], 0);
  // pixel 128: occ = 127/255 = 0.498; 99 * (0.498 - 0.196) / (0.65 - 0.196) = 65.9 -> 65
  EXPECT_EQ(m.data[2], 65);
}

TEST(MapImage, RawModeKeepsThePixelValue) {
  MapImageParams p;
  p.mode = MapMode::kRaw;
  const auto m = imageToOccupancy((cv::Mat_<uint8_t>(1, 3) << 0, 100, 255), p);
  EXPECT_EQ(m.data[0], 0);
  EXPECT_EQ(m.data[1], 100);
  EXPECT_EQ(m.data[2], -1);  // 255 as int8, as ROS stores it
}

TEST(MapImage, TopImageRowIsTheHighestMapRow) {
  const cv::Mat img = (cv::Mat_<uint8_t>(2, 2) << 0, 255, 255, 255);  // black pixel top-left
  const auto m = imageToOccupancy(img, MapImageParams{});
  // data row 1 (highest y) holds the image's top row.
  EXPECT_EQ(m.data[2], 100);
  EXPECT_EQ(m.data[0], 0);
}

TEST(MapImage, AlphaIsNotAveragedAndOnlyTransparencyMakesScaleUnknown) {
  // BGRA: opaque black, transparent black, opaque mid grey, transparent mid grey.
  cv::Mat img(1, 4, CV_8UC4);
  img.at<cv::Vec4b>(0, 0) = {0, 0, 0, 255};
  img.at<cv::Vec4b>(0, 1) = {0, 0, 0, 0};
  img.at<cv::Vec4b>(0, 2) = {128, 128, 128, 255};
  img.at<cv::Vec4b>(0, 3) = {128, 128, 128, 0};
  const auto tri = imageToOccupancy(img, MapImageParams{});
  // ROS would average alpha in: opaque black -> mean 63.75 -> still occupied, but white-ish walls
  // with alpha would shift; here the colour alone decides.
  EXPECT_EQ(tri.data[0], 100);
  EXPECT_EQ(tri.data[1], 100);  // thresholds come first, as in ROS
  EXPECT_EQ(tri.data[2], -1);
  MapImageParams p;
  p.mode = MapMode::kScale;
  const auto sc = imageToOccupancy(img, p);
  EXPECT_EQ(sc.data[2], 65);
  EXPECT_EQ(sc.data[3], -1);
  // A 3-channel image has no alpha: a mid grey with blue 0 is graded, not unknown.
  cv::Mat bgr(1, 1, CV_8UC3, cv::Scalar(0, 192, 192));
  EXPECT_EQ(imageToOccupancy(bgr, p).data[0], 65);
}

TEST(MapImage, SixteenBitImagesAreScaled) {
  const cv::Mat img = (cv::Mat_<uint16_t>(1, 2) << 0, 65535);
  const auto m = imageToOccupancy(img, MapImageParams{});
  EXPECT_EQ(m.data[0], 100);
  EXPECT_EQ(m.data[1], 0);
}

TEST(MapImage, ThresholdsOutOfOrderAreRefused) {
  MapImageParams p;
  p.occupied_thresh = 0.1;
  p.free_thresh = 0.5;
  try {
    imageToOccupancy(greyRow(), p);
    FAIL() << "thresholds out of order accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("free_thresh"), std::string::npos) << e.what();
  }
}

TEST(MapImage, PngWithAlphaLoadsFromFileAndBadFilesNameThePath) {
  const std::string png = testing::TempDir() + "map_image_alpha.png";
  cv::Mat img(2, 1, CV_8UC4);
  img.at<cv::Vec4b>(0, 0) = {255, 255, 255, 255};
  img.at<cv::Vec4b>(1, 0) = {128, 128, 128, 0};
  ASSERT_TRUE(cv::imwrite(png, img));
  MapImageParams p;
  p.mode = MapMode::kScale;
  const auto m = loadMapImage(png, p);
  EXPECT_EQ(m.data[1], 0);   // top pixel, white
  EXPECT_EQ(m.data[0], -1);  // bottom pixel, transparent grey
  std::remove(png.c_str());

  const std::string junk = testing::TempDir() + "map_image_junk.pgm";
  FILE* f = std::fopen(junk.c_str(), "w");
  std::fputs("not an image", f);
  std::fclose(f);
  for (const std::string& path : {junk, testing::TempDir() + "no_such_map.pgm"}) {
    try {
      loadMapImage(path, MapImageParams{});
      FAIL() << path << " loaded";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  std::remove(junk.c_str());
}
