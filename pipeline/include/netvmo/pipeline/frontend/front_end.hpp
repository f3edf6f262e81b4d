// The tag front end: detection + refinement + undistortion into what the observer consumes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// One camera's measurement of the target in one frame.
struct TagObservation {
  bool delta = false;  ///< delta_i(t): the target id was decoded and accepted
  TargetStatus status = TargetStatus::not_found;
  std::string reason;  ///< why the target was rejected (empty when detected)
  int tag_id = -1;     ///< the target id when detected, else -1
  int hamming = 0;
  double margin = 0.0;                      ///< decision margin of the accepted detection
  std::array<cv::Point2d, 4> corners_px{};  ///< refined corners, OpenCV pixels
  /// Undistorted normalized coordinates [x0,y0,x1,y1,x2,y2,x3,y3], corner k matching
  /// obs::FeatureModel::square(size).points_o[k]. Zero when not detected.
  Eigen::Matrix<double, 8, 1> f_normalized = Eigen::Matrix<double, 8, 1>::Zero();
};

/// Corners (OpenCV pixels) to the observer's feature vector f (undistorted normalized).
Eigen::Matrix<double, 8, 1> normalized_features(const std::array<cv::Point2d, 4>& corners_px,
                                                const io::Calibration& calib);

/// Tracking: while a camera keeps detecting the target, the next frame is searched first in a
/// window around the last corners; only when that fails (or every `full_frame_every` frames)
/// is the whole image searched. delta still comes from a real decode in this frame. Caveat:
/// while tracking, a second tag with the target's id outside the window is not seen, so the
/// duplicate-id rejection is checked on full-frame searches only.
struct TrackingSettings {
  bool enabled = true;
  double window_margin = 0.75;  ///< window = corner bounding box grown by this x its size ...
  int window_pad = 24;          ///< ... plus this many pixels on every side
  int full_frame_every = 30;    ///< a full-frame search at least this often (frames)
};

/// One camera's tracking state (keep one per camera, pass it on every frame).
struct TrackState {
  std::optional<std::array<cv::Point2d, 4>> last;  ///< corners of the last detection
  int frames_since_full = 0;
};

/// Detector (reused across frames and cameras) + refinement + cv::undistortPoints.
class FrontEnd {
 public:
  explicit FrontEnd(DetectorSettings settings = {}, TrackingSettings tracking = {})
      : detector_(std::move(settings)), tracking_(tracking) {}

  /// Runs on one camera's frame. An empty image (camera blind at that frame) gives
  /// detected = false. If `all` is given it receives every decoded tag of the frame (of the
  /// searched window when tracking). With `track`, the search is windowed as described above.
  TagObservation observe(const cv::Mat& gray, const io::Calibration& calib,
                         FrameDetections* all = nullptr, TrackState* track = nullptr);
  const TrackingSettings& tracking() const { return tracking_; }

  TagDetector& detector() { return detector_; }
  const DetectorSettings& settings() const { return detector_.settings(); }

 private:
  TagDetector detector_;
  TrackingSettings tracking_;
};

}  // namespace netvmo::frontend
