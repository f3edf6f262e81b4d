// The Embree renderer: scene in, images and ground truth out, in memory.
//
//   render::Renderer r(scene);              // builds and commits the static BVH once
//   cv::Mat img = r.render(cam_index, k);   // CV_8UC1, camera's true pose at frame k
//   render::FrameTruth gt = r.truth(cam_index, k);
//
// Static geometry lives in one Embree scene committed once and instanced with the identity;
// the target and moving occluders are instances whose transforms are updated per frame, after
// which only the small top-level scene is recommitted. render() and truth() may be called
// concurrently from several threads (e.g. one per camera); calls for a different frame wait
// until no call is using the current frame, then switch the frame.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <vector>

#include <opencv2/core.hpp>

#include "netvmo/render/scene.hpp"

namespace netvmo::render {

/// Ground truth of one camera in one frame (all from the true poses).
struct FrameTruth {
  int frame = 0;
  double t = 0;  ///< frame / fps [s]
  int camera_id = 0;
  Pose g_wo = Pose::Identity();  ///< true target pose in the world
  Pose g_io = Pose::Identity();  ///< true target pose in the camera = g_wi^-1 g_wo
  /// Tag corners c_k in the object frame: c0 (-s/2,-s/2,0), c1 (s/2,-s/2,0), c2 (s/2,s/2,0),
  /// c3 (-s/2,s/2,0), i.e. libapriltag's detection order; projected with distortion (OpenCV
  /// pixel centres). Empty (nullopt) for a corner behind the camera.
  std::array<std::optional<Vec2>, 4> corners;
  /// All four corners in front of the camera and inside the image (and inside the region where
  /// the distortion model is invertible).
  bool in_fov = false;
  /// Fraction of a grid of sample points over the printed tag (black square and white quiet
  /// zone, both needed for detection) that is front-facing,
  /// inside the field of view and not occluded along the line of sight (0..1).
  double visible_fraction = 0;
};

class Renderer {
 public:
  /// Validates the scene (std::invalid_argument with one line) and builds the Embree scene.
  explicit Renderer(SceneDescription scene);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const SceneDescription& scene() const { return scene_; }
  int camera_count() const { return static_cast<int>(scene_.cameras.size()); }
  int frame_count() const { return scene_.frames; }
  /// The time [s] of render frame `frame`: frame / fps, or its entry of set_frame_times().
  double time_of(int frame) const {
    return frame >= 0 && size_t(frame) < frame_times_.size() ? frame_times_[size_t(frame)]
                                                             : frame / scene_.fps;
  }
  /// Render frames at arbitrary times (cameras on their own clocks): frame k is at times[k]
  /// from now on (frames past the list stay at k / fps). Not thread-safe: call before
  /// rendering, not concurrently with render() or truth().
  void set_frame_times(std::vector<double> times);
  /// Index of the camera with this id; throws std::invalid_argument if unknown.
  int camera_index(int id) const;

  /// Moves the target and moving occluders to frame k and recommits the top-level scene.
  void set_frame(int frame);
  /// The 8-bit grayscale image of camera `camera_index` at `frame` (CV_8UC1, height x width).
  cv::Mat render(int camera_index, int frame);
  /// Fraction of the primary-ray packets of camera `camera_index`'s last image that were traced
  /// (the others reused its previous radiance, imaging.reuse_radiance); 1 before any image.
  double traced_fraction(int camera_index);
  /// Ground truth of camera `camera_index` at `frame`.
  FrameTruth truth(int camera_index, int frame);
  /// True pose of target `target` (index in SceneDescription::targets) at frame k.
  Pose target_pose(int frame, size_t target = 0) const;
  /// True pose of camera `camera_index` at frame k (it renders from there; static cameras:
  /// CameraSpec::g_wi_true).
  Pose camera_pose(int camera_index, int frame) const;
  /// Believed pose of camera `camera_index` at frame k (CameraSpec::believed_pose).
  Pose believed_camera_pose(int camera_index, int frame) const;

  /// Benchmark baseline: the same primary rays as render() (imaging.spp per pixel), traced one
  /// at a time with rtcIntersect1 and no shading, over `threads` threads. Returns the number of
  /// rays that hit something.
  std::uint64_t intersect_bare(int camera_index, int frame, int threads);

  struct Impl;

 private:
  /// Validates a camera index and frame, and holds the frame (switching to it when no other
  /// call is using the current one) for the lifetime of the returned lock.
  std::shared_lock<std::shared_mutex> acquire(int camera_index, int frame);

  SceneDescription scene_;
  std::vector<double> frame_times_;  ///< set_frame_times(); empty: k / fps
  std::unique_ptr<Impl> impl_;
};

}  // namespace netvmo::render
