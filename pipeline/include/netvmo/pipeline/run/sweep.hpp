// Gain sweeps on one dataset (`netvmo sweep`): the front end runs once and its outputs (the
// observer's inputs) are cached; each grid point (k_e, k_s) replays only the observer over them
// and is compared with Theorem 1's guarantee for k = k_e/k_s.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/metrics.hpp"
#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::run {

/// The observer's inputs of a whole dataset, from one front-end pass.
struct RecordedInputs {
  double dt = 0.0;
  std::vector<std::vector<obs::Measurement>> frames;  ///< [frame][camera]
  std::vector<std::optional<SE3>> targets;            ///< true target pose per frame, when known
};

/// One front-end pass over the source (run_images with its detector and tracking settings).
RecordedInputs record_inputs(sources::NetworkSource& source, const ImageRunSettings& options);

/// The cache of the front end's outputs: per frame and camera delta, the normalized corners and
/// the PnP pose (%.17g), after a first line naming the dataset, its frame and camera counts and
/// the detector settings. Ground truth is not stored (it is read from the dataset).
void write_inputs_cache(const std::filesystem::path& file, const sources::NetworkSource& source,
                        const ImageRunSettings& options, const RecordedInputs& in);
/// The cached inputs when `file` exists and its first line matches this dataset and these
/// settings (nullopt otherwise), with the truth taken from the source. Throws InputError
/// naming the file and line on a malformed row.
std::optional<RecordedInputs> read_inputs_cache(const std::filesystem::path& file,
                                                const sources::NetworkSource& source,
                                                const ImageRunSettings& options);

/// One grid point's results over the recorded frames (NaN where the data has no truth, or where
/// a quantity is undefined, e.g. a frame in which no camera has an estimate).
struct SweepPoint {
  double k_e = 0.0, k_s = 0.0;
  int rounds = 0;
  double step_factor = 0.0;
  double eps_p = 0.0, eps_R = 0.0;            ///< Definition 1, last frame with truth
  double eps_p_tail = 0.0, eps_R_tail = 0.0;  ///< sup over the last quarter of the frames
  double U_p = 0.0, U_R = 0.0;                ///< last frame with truth
  double worst_position_m = 0.0, worst_orientation_deg = 0.0;  ///< final error to g*
  obs::Theorem1Bound bound;  ///< Theorem 1 at k = k_e/k_s (infinite for k_s = 0; NaN without truth)
  // Defined without ground truth (what a recorded dataset of real cameras gives):
  /// Definition 1 at the last frame where every camera has an estimate and one has a PnP pose,
  /// with g* and rho taken from the detecting cameras' measured fictitious poses g_wi g_io,PnP
  /// (their average and spread) instead of the true ones.
  double eps_p_measured = 0.0, eps_R_measured = 0.0;
  /// The largest difference between two cameras' networked estimates g_wi g_bar_i, last frame.
  double disagreement_m = 0.0, disagreement_deg = 0.0;
  /// Convergence: the largest frame-to-frame move of a camera's networked estimate over the last
  /// quarter of the frames.
  double last_quarter_step_m = 0.0, last_quarter_step_deg = 0.0;
};

/// The graph quantities the bound needs, and the spread of the last frame's visible set.
struct SweepContext {
  obs::Graph graph;
  std::vector<SE3> g_wi;
  double W = 0.0;
  int diameter = 0;
  obs::Spread spread;
  int n_visible = 0;
  /// Ground truth known (some camera's true g_io in some frame): g*, the eps-levels against it,
  /// the energies, the final errors and Theorem 1's bound are defined.
  bool truth = false;
  /// The spread of the last frame's detecting cameras' measured fictitious poses (PnP), and their
  /// number: defined without truth.
  obs::Spread measured_spread;
  int n_measured = 0;
};
SweepContext sweep_context(const io::NetworkConfig& net, const RecordedInputs& in);

/// Replays the observer (settings, with k_e and k_s of the point) over the inputs.
SweepPoint sweep_point(const SweepContext& c, RunnerSettings settings, const RecordedInputs& in);

/// Parses a comma-separated list of gains for `option` ("--ks"); throws InputError naming the
/// option and the bad item (not a number, negative, zero when !allow_zero, repeated, or empty).
std::vector<double> parse_gain_list(const std::string& option, const std::string& text,
                                    bool allow_zero);

/// Writes sweep.csv (one row per point, the bound next to the measurement; a blank line between
/// runs of different k_e, so gnuplot draws one line per k_e) atomically.
void write_sweep_csv(const std::filesystem::path& file, const std::vector<SweepPoint>& points);

/// A column of sweep.csv (1-based, as gnuplot counts), with whether it is defined (finite) at
/// some grid point of `points`.
struct SweepColumn {
  const char* name;
  int index;
  bool defined;
};
/// Every column of sweep.csv after k_e, k_s, k, rounds and step_factor, in file order.
std::vector<SweepColumn> sweep_columns(const std::vector<SweepPoint>& points);

}  // namespace netvmo::run
