// Overlays of a run: per camera an MP4 with the detected corners (green, corner 0 marked) and
// the networked observer's estimate reprojected (magenta), plus a mosaic of all cameras as an
// MP4 and, for the last frame, a PNG. Several targets: each target in its own pair of colours
// (target_colors), named in the legend by its primary tag's id.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/videoio.hpp>
#include <vector>

#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::run {

struct OverlaySettings {
  bool video = true;          ///< per-camera MP4s and mosaic.mp4
  int mosaic_columns = 3;     ///< cameras per mosaic row
  double mosaic_scale = 0.5;  ///< each camera's size in the mosaic
};

/// What one camera's overlay draws of one target: its front-end result, the camera's record of
/// the target's networked observer, and the target (the estimate is drawn as its primary tag's
/// square).
struct OverlayLayer {
  const CameraFrame* cam = nullptr;
  const run::CameraRecord* rec = nullptr;
  const io::TargetConfig* target = nullptr;
};

/// Detection and estimate colours (BGR) of target j: green and magenta for the first, then
/// other distinct pairs (cycling after 4).
std::pair<cv::Scalar, cv::Scalar> target_colors(size_t j);

/// Draws one camera's overlay of a frame (BGR), one layer per target.
cv::Mat draw_overlay(const cv::Mat& gray, int camera_id, const io::Calibration& calib,
                     const obs::SE3& g_wi, const std::vector<OverlayLayer>& layers);

/// A FrameHook that writes DIR/overlays/cam_<id>.mp4, DIR/overlays/mosaic.mp4 and, on finish(),
/// DIR/overlays/mosaic.png of the last frame.
class OverlayWriter {
 public:
  OverlayWriter(const std::filesystem::path& dir, const sources::NetworkSource& provider,
                OverlaySettings settings = {});
  /// A FrameHook: cams [target][camera], one record per target.
  void operator()(int frame, const std::vector<cv::Mat>& images,
                  const std::vector<std::vector<CameraFrame>>& cams,
                  const std::vector<const run::FrameRecord*>& records);
  /// Closes the videos and writes the last mosaic as PNG.
  void finish();

 private:
  std::filesystem::path dir_;
  const sources::NetworkSource& provider_;
  OverlaySettings settings_;
  std::vector<cv::VideoWriter> videos_;
  cv::VideoWriter mosaic_video_;
  cv::Mat last_mosaic_;
};

}  // namespace netvmo::run
