// One camera's step from a frame to the observer's input, written once for `run` (run_images,
// and `sweep` through it), `node` and `detect`: read the image, the front end (every target decided
// in one pass, the camera's tracking state carried from frame to frame), PnP of each detected
// target on the corners of its accepted tags (CameraFrame), then the observer's Measurement of it
// (camera_input).
#pragma once

#include <exception>
#include <functional>
#include <optional>
#include <vector>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/run/runner.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::run {

/// What one camera made of one frame, for one target.
struct CameraFrame {
  frontend::TagObservation obs;      ///< detection (delta, corners, normalized features)
  std::optional<obs::SE3> g_io_pnp;  ///< ViSP pose when detected
  /// g_io_pnp's first-order covariance from the corners' (frontend::pnp_covariance: the tag's
  /// position and rotation in the camera frame, ROS's PoseWithCovariance order).
  std::optional<frontend::PoseCovariance> pnp_covariance;
  /// The object points of obs.f_normalized when the target has a bundle (tag_points of the
  /// accepted tags; empty for a single tag, whose points are the error model's fixed square).
  std::vector<obs::Vec3> points_o;
  bool read_failed = false;  ///< the image could not be read (only with keep_going)
};

/// One camera's step on one image, written once for `run` (run_images, and `sweep` through it),
/// `node` and `detect`: `read` the image into `image` (an InputError from it, an unreadable
/// image, is returned, not thrown: the camera is blind in that frame, its front end run on no
/// image as on any blind frame, and with `keep_going` every CameraFrame is marked read_failed;
/// any other error propagates), the front end on every target (front_end's targets, set with
/// frontend::set_targets; `targets` the same list), the camera's tracking state carried in
/// `track`, and with `pnp` the PnP pose and its covariance of each detected target. One
/// CameraFrame per target into `out`; every decoded tag into `all` (optional);
/// `seconds_reading` (optional) is increased by the time a successful read took.
std::exception_ptr observe_camera(const std::function<cv::Mat()>& read,
                                  const io::Calibration& calib, frontend::FrontEnd& front_end,
                                  frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<CameraFrame>& out,
                                  double* seconds_reading = nullptr,
                                  frontend::FrameDetections* all = nullptr, bool pnp = true);

/// The same on camera i's frame `frame` of `source`.
std::exception_ptr observe_camera(sources::NetworkSource& source, size_t i, int frame,
                                  frontend::FrontEnd& front_end, frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<CameraFrame>& out,
                                  double* seconds_reading = nullptr);

/// One camera's observer input (camera_inputs, for one camera; true_wi: its true pose, if known).
CameraInput camera_input(const CameraFrame& cam, const std::optional<obs::SE3>& target,
                         const std::optional<obs::SE3>& true_wi);

/// One frame's observer inputs: delta, the normalized corners and the PnP pose from the front
/// end, and on data with truth the true relative pose g_io = g_wi^-1 g_wo (true_wi: the
/// cameras' true poses, when known).
std::vector<CameraInput> camera_inputs(const std::vector<CameraFrame>& cams,
                                       const std::optional<obs::SE3>& target,
                                       const std::vector<std::optional<obs::SE3>>& true_wi);

}  // namespace netvmo::run
