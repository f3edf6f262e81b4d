// Overlays of a run: per camera an MP4 with the detected corners (green, corner 0 marked) and
// the networked observer's estimate reprojected (magenta), plus a mosaic of all cameras as an
// MP4 and, for the last frame, a PNG.
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

/// Draws one camera's overlay of a frame (BGR).
cv::Mat draw_overlay(const cv::Mat& gray, int camera_id, const io::Calibration& calib,
                     const obs::SE3& g_wi, const CameraFrame& cam, const run::CameraRecord& rec,
                     double tag_size);

/// A FrameHook that writes DIR/overlays/cam_<id>.mp4, DIR/overlays/mosaic.mp4 and, on finish(),
/// DIR/overlays/mosaic.png of the last frame.
class OverlayWriter {
 public:
  OverlayWriter(const std::filesystem::path& dir, const sources::NetworkSource& provider,
                OverlaySettings settings = {});
  void operator()(int frame, const std::vector<cv::Mat>& images,
                  const std::vector<CameraFrame>& cams, const run::FrameRecord& record);
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
