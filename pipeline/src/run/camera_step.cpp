#include "netvmo/pipeline/run/camera_step.hpp"

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::run {

std::exception_ptr observe_camera(const std::function<cv::Mat()>& read,
                                  const io::Calibration& calib, frontend::FrontEnd& front_end,
                                  frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<frontend::Observation>& out,
                                  double* seconds_reading, frontend::FrameDetections* all,
                                  bool pnp) {
  std::exception_ptr unreadable;
  const auto t0 = Clock::now();
  try {
    image = read();
    if (seconds_reading) *seconds_reading += seconds_since(t0);
  } catch (const InputError&) {
    image.release();
    unreadable = std::current_exception();
  }
  // The camera's first image read: resampled by nearest neighbour? (a warning for the user)
  if (!track.resampling && !image.empty() && image.type() == CV_8UC1)
    track.resampling = frontend::measure_resampling(image);
  // An unreadable image is a blind frame for the front end too (its tracking state).
  out = front_end.observe_targets(image, calib, all, &track);
  for (size_t j = 0; j < targets.size(); ++j) {
    frontend::Observation& o = out[j];
    o.read_failed = unreadable && keep_going;
    if (!o.delta || !pnp) continue;
    // PnP on the corners of every accepted tag (a bundle's object points).
    const auto m = frontend::observation_model(targets[j], o);
    const auto pose = frontend::pnp_pose(o.f_normalized, m);
    if (pose) {
      o.g_io_pnp = pose->g_io;
      if (const auto f_cov = frontend::f_covariance_matrix(o))
        o.pnp_covariance = frontend::pnp_covariance(pose->g_io, m.points_o, *f_cov);
    }
    if (!targets[j].bundle.empty()) o.points_o = m.points_o;
  }
  return unreadable;
}

std::exception_ptr observe_camera(sources::NetworkSource& source, size_t i, int frame,
                                  frontend::FrontEnd& front_end, frontend::TrackState& track,
                                  const std::vector<io::TargetConfig>& targets, bool keep_going,
                                  cv::Mat& image, std::vector<frontend::Observation>& out,
                                  double* seconds_reading) {
  return observe_camera([&] { return source.read(i, frame); }, source.calibration(i), front_end,
                        track, targets, keep_going, image, out, seconds_reading);
}

obs::Measurement measurement_of(const frontend::Observation& o,
                                const std::optional<obs::SE3>& target,
                                const std::optional<obs::SE3>& true_wi) {
  obs::Measurement z;
  z.delta = o.delta;
  z.f = o.f_normalized;     // (eq:visual_mea) with lambda = 1
  z.points_o = o.points_o;  // a bundle's seen corners (empty: the tag's square)
  z.g_io_pnp = o.g_io_pnp;
  if (target && true_wi) z.g_io_true = true_wi->inverse() * *target;  // g_io = g_wi^-1 g_wo
  return z;
}

std::vector<obs::Measurement> measurements_of(const std::vector<frontend::Observation>& cams,
                                              const std::optional<obs::SE3>& target,
                                              const std::vector<std::optional<obs::SE3>>& true_wi) {
  std::vector<obs::Measurement> z(cams.size());
  for (size_t i = 0; i < cams.size(); ++i) z[i] = measurement_of(cams[i], target, true_wi[i]);
  return z;
}

}  // namespace netvmo::run
