// Images -> front end -> networked observer, frame by frame. delta_i(t) is the front end's
// detection success; ground truth, when the source has it, is used only for evaluation and
// for the `exact` error model.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/run/camera_step.hpp"
#include "netvmo/pipeline/run/flips.hpp"
#include "netvmo/pipeline/run/runner.hpp"
#include "netvmo/pipeline/run/transports.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::run {

struct ImageRunSettings {
  run::RunnerSettings runner;  ///< gains, error model, initialisation, rounds (tag size: dataset)
  frontend::DetectorSettings
      detector;  ///< detector settings (family and target id: from the dataset)
  frontend::TrackingSettings tracking;  ///< windowed search around the last detection
  TransportSettings transport;          ///< how estimates travel between cameras (transports.hpp)
  bool keep_going = false;  ///< an unreadable image blinds its camera for that frame (warning)
                            ///< instead of stopping the run
  int workers = 2;          ///< threads detecting cameras in parallel (one detector each)
  std::optional<int> max_frames;  ///< stop after this many frames
  bool progress = true;           ///< progress bar on stderr
  FlipSettings flips;             ///< what summary.json counts as a pose flip (flips.hpp)
  /// Moving cameras (NetworkSource::cameras_move): still feed each frame's believed poses but
  /// set every V_wi to zero (a diagnostic: how much the -hat(V_wi) g_bar term of (eq:EsRRBM)
  /// matters).
  bool ignore_camera_velocity = false;
};

/// Called after each frame with the frame's images, the front-end results [target][camera] and
/// each target's record (one target unless network.yaml lists several).
using FrameHook = std::function<void(int frame, const std::vector<cv::Mat>& images,
                                     const std::vector<std::vector<frontend::Observation>>& cams,
                                     const std::vector<const run::FrameRecord*>& records)>;

/// One camera's estimate after one of its own images: a row of estimates.csv when the cameras
/// run on their own clocks.
struct OwnClockRecord {
  int frame = 0;      ///< the camera's own frame index
  double t = 0.0;     ///< the image's time [s]
  size_t camera = 0;  ///< index in network.yaml
  bool delta = false;
  bool initialized = false;
  obs::SE3 est_w = obs::SE3::Identity();
};

/// A run's results. The per-target fields (history, frames, own_estimates) are the first
/// target's; with several targets (network.yaml `targets:`) other_targets holds the others'.
struct ImageRunResult {
  /// Every frame's record and front-end results; only the last record when
  /// runner.keep_history is false (then `frames` stays empty).
  std::vector<run::FrameRecord> history;
  std::vector<std::vector<frontend::Observation>> frames;  ///< [frame][camera]
  std::vector<std::string> warnings;
  int substeps = 0;
  double step_factor = 0.0;
  double seconds = 0.0;            ///< wall time of the loop
  double seconds_front_end = 0.0;  ///< of which reading + detection + PnP
  double seconds_observer = 0.0;   ///< of which the observer and baselines
  /// The front end's time by stage, summed over its worker threads (so up to `workers` times
  /// seconds_front_end): reading the images (file and decoding; rendering for a live source)
  /// and the detector's stages (frontend::StageSeconds).
  double seconds_reading = 0.0;
  frontend::StageSeconds seconds_stages;
  /// Cameras on their own clocks (async processes at different rates): estimates.csv holds
  /// these rows (each camera's own images and times, by t, then camera), while history and
  /// frames are a regular grid at the dataset's fps holding each camera's latest estimate at or
  /// before each grid time. Empty: estimates.csv is written from history.
  std::vector<OwnClockRecord> own_estimates;
  /// With own_estimates: [grid frame][camera] the camera's own frame held there (-1: none yet).
  std::vector<std::vector<int>> source_frames;
  /// The clock of the result's files (their `t` column), summary.json's time_origin_s. Cameras
  /// on their own clocks: t = the dataset's time (timestamps.csv's) less this, 0 for run, the
  /// grid's t0 for a merge (it counts from the earliest image). Empty: one clock, t = frame / fps
  /// whatever times the dataset lists.
  std::optional<double> time_origin_s;
  /// `netvmo run` on cameras on their own clocks: the observer advanced on the union of their
  /// image times (run_images); summary.json says so.
  bool union_of_timestamps = false;
  /// Several targets: targets 1, 2, ... of network.yaml, each with its own history, frames and
  /// own_estimates (their other fields are unused: the run's are this result's).
  std::vector<ImageRunResult> other_targets;
  /// Target j's per-target fields (0: this result).
  ImageRunResult& target(size_t j) { return j == 0 ? *this : other_targets.at(j - 1); }
  const ImageRunResult& target(size_t j) const { return j == 0 ? *this : other_targets.at(j - 1); }
  size_t target_count() const { return 1 + other_targets.size(); }
};

/// The regular grid on which runs of cameras on their own clocks are evaluated (the energies,
/// epsilon-levels and errors against g*(t)): t0 + k dt, k < frames, t0 = the earliest first
/// image of any camera, dt = 1 / the dataset's fps.
struct TimeGrid {
  double t0 = 0.0;
  double dt = 0.0;
  int frames = 0;
  double time(int k) const { return t0 + k * dt; }
};
/// The grid of a source: `frames` grid times, or when 0 every grid time up to the last image of
/// any camera (1e-9 s slack).
TimeGrid time_grid(const sources::NetworkSource& source, int frames = 0);
/// The grid from `first` to `last` (the earliest and latest image times) at `dt`: `frames` grid
/// times, or when 0 every one up to `last` (1e-9 s slack).
TimeGrid time_grid(double first, double last, double dt, int frames = 0);
/// What a camera holds at time t: the index of its latest image at or before t (times in
/// increasing order, 1e-9 s slack), or -1 before its first.
int latest_at_or_before(const std::vector<double>& times, double t);

/// The communication graph of network.yaml (camera indices in its order). Throws InputError
/// naming network.yaml when it is disconnected (Assumption 1).
obs::Graph network_graph(const io::NetworkConfig& net);

/// The warning a run gives when h (k_e + 2 k_s d_max) = step_factor reaches 2 (the forward-Euler
/// stability limit), or none.
std::optional<std::string> step_factor_warning(int substeps, double step_factor);

/// The most exchange rounds per frame a run accepts (--rounds, or the smallest stable count the
/// gains need). Each round is one observer step of every camera (and, across processes, one
/// message round trip): 10,000 rounds cost ~50 ms per frame for 5 cameras in one process and
/// ~0.25 s over DDS (25 us a round), so such a run no longer keeps up with a camera; beyond the
/// smallest stable count more rounds only shrink the O(h) Euler error. 10^9 would take hours
/// per frame.
inline constexpr int kMaxRoundsPerFrame = 10000;

/// The exchange rounds per frame of a run: `rounds`, or when 0 the smallest N with
/// h (k_e + 2 k_s d_max) <= 1, h = dt / N (the step-factor rule of docs/observer.md,
/// "Discretisation and stability"). Throws InputError naming --rounds (or --ke/--ks when the gains
/// need too many) with the stable range when the count exceeds kMaxRoundsPerFrame or the gains are
/// not finite.
int checked_rounds(double dt, double k_e, double k_s, int max_degree, int rounds);

/// Body velocity that carries a camera from g_k to g_k1 in dt along the geodesic:
/// V = log(g_k^-1 g_k1) / dt, so g_k exp(dt hat(V)) = g_k1 (zero when the poses are equal).
obs::Vec6 camera_velocity(const obs::SE3& g_k, const obs::SE3& g_k1, double dt);

/// Runs the whole network over the source's frames. Several targets (network.yaml
/// `targets:`): the front end decides every target in one pass over each image (FrontEnd::
/// observe_targets) and each target has its own networked observer (its own Runner with
/// its tag size), delta_i, g* and metrics, all stepped on the same times.
///
/// Cameras on their own clocks (sources::clock_mismatch: their own fps, or different times for
/// the same frame index): the run is on the union of every camera's image times
/// (sources::camera_images). The network starts once every camera has taken its first image
/// (earlier images only set their cameras' held measurements, so each camera that sees the
/// target starts from its own PnP pose as in a synchronised run). Events in time order; between
/// two consecutive times (events and
/// grid times) every camera's estimate is integrated over the real elapsed time, in pieces of at
/// most 1 / fps, each with the run's sub-step rule (so h <= the step checked_rounds allows); a
/// camera's image updates only its own delta_i and measurement, which it holds until its next
/// image. history and frames are on time_grid(source) (max_frames grid times at most), each
/// record holding the estimates at that time, the held detections and g*(t) from the truth at
/// t (target_truth_at, camera_truth_at); own_estimates hold every camera image's row (its
/// frame, time and its camera's estimate at that time). The front end still runs on `workers`
/// threads, each camera's images in order on one thread. The hook is called at grid times with
/// each camera's latest image.
///
/// Moving cameras: before frame k the
/// runner gets every camera's believed pose g_wi(t_k) and the body velocity
/// camera_velocity(g_wi(t_k), g_wi(t_k+1), dt), held over the frame's sub-steps
/// (Runner::set_camera_motion); the ground truth is each frame's. Throws InputError for
/// bad input (an unreadable image without keep_going, a disconnected graph, an unknown camera
/// id).
ImageRunResult run_images(sources::NetworkSource& source, const ImageRunSettings& options,
                          const FrameHook& hook = {});

}  // namespace netvmo::run
