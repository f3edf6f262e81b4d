// The tag front end: detection + refinement + undistortion into what the observer consumes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>

#include "netvmo/pipeline/calibration.hpp"
#include "netvmo/pipeline/tag_detector.hpp"

namespace netvmo::pipeline {

/// One camera's measurement of the target in one frame.
struct TagObservation {
  bool detected = false;          ///< delta_i(t): the target id was decoded and accepted
  TargetStatus status = TargetStatus::not_found;
  int tag_id = -1;                ///< the target id when detected, else -1
  int hamming = 0;
  double margin = 0.0;            ///< decision margin of the accepted detection
  std::array<cv::Point2d, 4> corners_px{};  ///< refined corners, OpenCV pixels
  /// Undistorted normalized coordinates [x0,y0,x1,y1,x2,y2,x3,y3], corner k matching
  /// obs::FeatureModel::square(size).points_o[k]. Zero when not detected.
  Eigen::Matrix<double, 8, 1> f_normalized = Eigen::Matrix<double, 8, 1>::Zero();
};

/// Corners (OpenCV pixels) to the observer's feature vector f (undistorted normalized).
Eigen::Matrix<double, 8, 1> normalized_features(const std::array<cv::Point2d, 4>& corners_px,
                                                const Calibration& calib);

/// Detector (reused across frames and cameras) + refinement + cv::undistortPoints.
class FrontEnd {
 public:
  explicit FrontEnd(DetectorSettings settings = {}) : detector_(std::move(settings)) {}

  /// Runs on one camera's frame. An empty image (camera blind at that frame) gives
  /// detected = false. If `all` is given it receives every decoded tag of the frame.
  TagObservation observe(const cv::Mat& gray, const Calibration& calib,
                         FrameDetections* all = nullptr);

  TagDetector& detector() { return detector_; }
  const DetectorSettings& settings() const { return detector_.settings(); }

 private:
  TagDetector detector_;
};

}  // namespace netvmo::pipeline
