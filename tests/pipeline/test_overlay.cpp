// The overlay's image: a camera's frame reduced to its mosaic tile is its box-filtered average
// (every pixel of the frame weighs the same), whatever the reduction's steps.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "netvmo/pipeline/run/overlay.hpp"

namespace netvmo::run {
namespace {

// The drawn image's grey rows between the label (top) and the legend (bottom) against one
// INTER_AREA resize of the same frame: within one grey level (rounding of the two steps).
void expect_area_average(const cv::Mat& gray, double scale) {
  io::Calibration calib;
  calib.width = gray.cols;
  calib.height = gray.rows;
  const cv::Mat drawn = draw_overlay(gray, 1, calib, obs::SE3(), {}, scale);
  cv::Mat want;
  cv::resize(gray, want, drawn.size(), 0, 0, cv::INTER_AREA);
  ASSERT_EQ(drawn.type(), CV_8UC3);
  cv::Mat got;
  cv::cvtColor(drawn, got, cv::COLOR_BGR2GRAY);
  const cv::Rect middle(0, drawn.rows / 4, drawn.cols, drawn.rows / 2);
  cv::Mat diff;
  cv::absdiff(got(middle), want(middle), diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  EXPECT_LE(worst, 1.0) << gray.size() << " at scale " << scale;
}

TEST(Overlay, TileIsTheFramesAreaAverage) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 255);
  for (const cv::Size size : {cv::Size(1280, 720), cv::Size(1920, 1080), cv::Size(641, 481)}) {
    cv::Mat noise(size, CV_8UC1);
    for (int r = 0; r < noise.rows; ++r)
      for (int c = 0; c < noise.cols; ++c)
        noise.at<uint8_t>(r, c) = static_cast<uint8_t>(level(rng));
    // A one-pixel checkerboard: its average is mid-grey everywhere, where a reduction that
    // samples instead of averaging shows black and white.
    cv::Mat checker(size, CV_8UC1);
    for (int r = 0; r < checker.rows; ++r)
      for (int c = 0; c < checker.cols; ++c) checker.at<uint8_t>(r, c) = ((r + c) % 2) ? 255 : 0;
    for (const double scale : {0.25, 320.0 / size.width, 0.5, 0.4}) {
      expect_area_average(noise, scale);
      expect_area_average(checker, scale);
    }
  }
}

}  // namespace
}  // namespace netvmo::run
