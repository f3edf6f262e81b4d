// One camera's step from a frame to the observer's input, written once for `run` (run_images,
// and `sweep` through it), `node` and `detect`: read the image, the front end (every target decided
// in one pass, the camera's tracking state carried from frame to frame), PnP of each detected
// target on the corners of its accepted tags: frontend::Observation; then the observer's
// obs::Measurement of it (measurement_of).
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

/// One camera's step on one image, written once for `run` (run_images, and `sweep` through it),
/// `node` and `detect`: `read` the image into `image` (an InputError from it, an unreadable
/// image, is returned, not thrown: the camera is blind in that frame, its front end run on no
/// image as on any blind frame, and with `keep_going` every frontend::Observation is marked
/// read_failed; any other error propagates), the front end on every target (front_end's targets,
/// set with frontend::set_targets; `targets` the same list), the camera's tracking state carried in
/// `track`, and with `pnp` the PnP pose and its covariance of each detected target. One
/// frontend::Observation per target into `out`; every decoded tag into `all` (optional);
/// `seconds_reading` (optional) is increased by the time a successful read took.
std::exception_ptr observe_camera(const std::function<cv::Mat()>& read,
                                  const io::Calibration& calib, frontend::FrontEnd& front_end,
                                  frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<frontend::Observation>& out,
                                  double* seconds_reading = nullptr,
                                  frontend::FrameDetections* all = nullptr, bool pnp = true);

/// The same on camera i's frame `frame` of `source`.
std::exception_ptr observe_camera(sources::NetworkSource& source, size_t i, int frame,
                                  frontend::FrontEnd& front_end, frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<frontend::Observation>& out,
                                  double* seconds_reading = nullptr);

/// One camera's measurement (the observer's input) from its observation: delta, the normalized
/// corners and the PnP pose from the front end, and on data with truth the true relative pose
/// g_io = g_wi^-1 g_wo (target: the true target pose, true_wi: the camera's true pose, if known).
obs::Measurement measurement_of(const frontend::Observation& o,
                                const std::optional<obs::SE3>& target,
                                const std::optional<obs::SE3>& true_wi);

/// The same for every camera of a frame (true_wi: the cameras' true poses, when known).
std::vector<obs::Measurement> measurements_of(const std::vector<frontend::Observation>& cams,
                                              const std::optional<obs::SE3>& target,
                                              const std::vector<std::optional<obs::SE3>>& true_wi);

}  // namespace netvmo::run
