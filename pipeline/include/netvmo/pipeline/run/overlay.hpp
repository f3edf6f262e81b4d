// Overlays of a run: a mosaic of all cameras (each camera's image with the detected corners,
// corner 0 marked, and the networked observer's estimate reprojected) as an MP4 and, for the last
// frame, a PNG; on request (OverlaySettings::camera_videos) also an MP4 per camera at the
// camera's full resolution. Several targets: each target in its own pair of colours
// (target_colors), named in the legend by its primary tag's id.
//
// Cost: the mosaic is drawn at its tiles' size (each image is first reduced to its tile, then
// drawn on), so a frame costs about the same at 640x480 and at 1920x1080; and the drawing and
// video encoding run on a thread of their own, off the run's critical path (OverlayWriter).
#pragma once

#include <array>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <opencv2/videoio.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::run {

struct OverlaySettings {
  bool video = true;           ///< mosaic.mp4 (and the per-camera MP4s when camera_videos)
  bool camera_videos = false;  ///< overlays/cam_<id>.mp4 per camera at full resolution
  int mosaic_columns = 3;      ///< cameras per mosaic row
  int tile_width = 320;        ///< each camera's width in the mosaic [px] (its aspect kept)
  /// Frames the run may be ahead of the writer thread before it waits (bounds the memory the
  /// queued images hold).
  int queue_frames = 4;
};

/// What one camera's overlay draws of one target: its front end's corners (when it detected the
/// target), its networked estimate (when initialised; drawn as the target's primary tag's
/// square) and the target.
struct OverlayLayer {
  bool detected = false;
  std::array<cv::Point2d, 4> corners{};  ///< pixels, when detected
  bool read_failed = false;              ///< the camera's image could not be read
  std::optional<obs::SE3> estimate_w;    ///< the camera's estimate in the world frame
  const io::TargetConfig* target = nullptr;
};

/// Detection and estimate colours (BGR) of target j: green and magenta for the first, then
/// other distinct pairs (cycling after 4).
std::pair<cv::Scalar, cv::Scalar> target_colors(size_t j);

/// Draws one camera's overlay of a frame (BGR), one layer per target, at `scale` times the
/// camera's resolution (the gray image is reduced first; points are drawn at their scaled
/// positions, (u + 1/2) scale - 1/2).
cv::Mat draw_overlay(const cv::Mat& gray, int camera_id, const io::Calibration& calib,
                     const obs::SE3& g_wi, const std::vector<OverlayLayer>& layers,
                     double scale = 1.0);

/// Camera i's overlay layers of a frame, one per target: its detection and estimate (cams
/// [target][camera], one record per target).
std::vector<OverlayLayer> overlay_layers(
    const io::NetworkConfig& net, size_t i,
    const std::vector<std::vector<frontend::Observation>>& cams,
    const std::vector<const run::FrameRecord*>& records);

/// A FrameHook that writes DIR/overlays/mosaic.mp4, on finish() DIR/overlays/mosaic.png of the
/// last frame, and with camera_videos DIR/overlays/cam_<id>.mp4. The hook copies what a frame's
/// overlay needs (the images by reference: the run reads a new image every frame) and hands it
/// to the writer thread; an error of that thread (a video that cannot be written) is rethrown by
/// the next call or by finish().
class OverlayWriter {
 public:
  OverlayWriter(const std::filesystem::path& dir, const sources::World& world,
                OverlaySettings settings = {});
  ~OverlayWriter();
  OverlayWriter(const OverlayWriter&) = delete;
  OverlayWriter& operator=(const OverlayWriter&) = delete;
  /// A FrameHook: cams [target][camera], one record per target.
  void operator()(int frame, const std::vector<cv::Mat>& images,
                  const std::vector<std::vector<frontend::Observation>>& cams,
                  const std::vector<const run::FrameRecord*>& records);
  /// Waits for the writer thread, closes the videos and writes the last mosaic as PNG.
  void finish();

 private:
  /// One frame's overlay data, owned (the run's own objects change on the next frame).
  struct Job {
    std::vector<cv::Mat> images;
    std::vector<std::vector<OverlayLayer>> layers;  ///< [camera][target]
    std::vector<obs::SE3> g_wi;                     ///< believed camera poses
  };
  void draw(const Job& job);
  void work();
  void rethrow_error();

  std::filesystem::path dir_;
  const sources::World& world_;
  OverlaySettings settings_;
  std::vector<cv::VideoWriter> videos_;
  cv::VideoWriter mosaic_video_;
  cv::Mat last_mosaic_;
  // The writer thread and its queue.
  std::mutex mu_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  bool closing_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace netvmo::run
