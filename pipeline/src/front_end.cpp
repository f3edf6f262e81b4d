#include "netvmo/pipeline/front_end.hpp"

namespace netvmo::pipeline {

Eigen::Matrix<double, 8, 1> normalized_features(const std::array<cv::Point2d, 4>& corners_px,
                                                const Calibration& calib) {
  const auto xy = normalize_points(std::vector<cv::Point2d>(corners_px.begin(), corners_px.end()),
                                   calib);
  Eigen::Matrix<double, 8, 1> f;
  for (int k = 0; k < 4; ++k) {
    f[2 * k] = xy[static_cast<size_t>(k)].x;
    f[2 * k + 1] = xy[static_cast<size_t>(k)].y;
  }
  return f;
}

TagObservation FrontEnd::observe(const cv::Mat& gray, const Calibration& calib,
                                 FrameDetections* all) {
  TagObservation obs;
  FrameDetections dets;
  if (!gray.empty()) dets = detector_.detect(gray, &calib);
  obs.status = dets.status;
  if (const TagDetection* t = dets.target()) {
    obs.detected = true;
    obs.tag_id = t->id;
    obs.hamming = t->hamming;
    obs.margin = t->margin;
    obs.corners_px = t->corners;
    obs.f_normalized = normalized_features(t->corners, calib);
  }
  if (all) *all = std::move(dets);
  return obs;
}

}  // namespace netvmo::pipeline
