// The frame-by-frame runner: front-end measurements in, the networked observer and its
// baselines stepped, the paper's metrics evaluated against ground truth when it is known.
// Images never reach this file: it consumes one obs::Measurement per camera and frame.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"

namespace netvmo::run {

using obs::SE3;

enum class InitMode {
  Pnp,   ///< a camera starts from its first PnP pose, or from its neighbours' estimates
  Paper  ///< every camera starts at g_bar(0) = ([0,0,1], R_facing) (see RunnerSettings)
};
InitMode parse_init_mode(const std::string& s);
const char* to_string(InitMode m);

struct RunnerSettings {
  /// The networked estimator, by its registry name (observer/estimator.hpp): vmo (the paper's)
  /// or zero-offset.
  std::string estimator = "vmo";
  /// Further networked estimators run on the same measurements with the same gains, reported
  /// as baselines (empty by default).
  std::vector<std::string> compare_estimators;
  double k_e = 1.0;   ///< visual feedback gain
  double k_s = 50.0;  ///< mutual feedback gain
  /// Visual error model of (eq:input_f-), by its registry name (observer/error_model.hpp):
  /// pnp (the camera's own PnP pose), jacobian (the tag's corners), exact (ground truth).
  std::string error_model = "pnp";
  InitMode init = InitMode::Pnp;  ///< initial estimates
  int rounds = 0;                 ///< exchange rounds (sub-steps) per frame; 0 = stable
  double tag_size = 0.2;          ///< side of the tag's black square [m]
  /// A feature-model estimate whose tag corner comes closer to the camera plane than this is
  /// re-initialised from PnP when the camera sees the target (its image features are undefined).
  double min_feature_depth = 0.05;
  /// Keep every frame's record in history() (for the outputs). false: only the latest frame's,
  /// so memory stays flat over arbitrarily long runs (the soak).
  bool keep_history = true;
};

/// The paper's initial estimate for image runs: 1 m in front of the camera, tag facing it
/// (R = diag(1,-1,-1), the camera-frame form of the printed identity orientation).
SE3 paper_initial_estimate();

/// One camera's state after a frame.
struct CameraRecord {
  bool delta = false;
  bool initialized = false;         ///< the networked estimate exists
  SE3 est_w = SE3::Identity();      ///< networked estimate in the world, g_wi g_bar_i
  std::optional<SE3> indep_w;       ///< independent observer (k_s = 0), once it has seen the tag
  std::optional<SE3> pnp_w;         ///< g_wi g_io,PnP (when delta)
  std::optional<SE3> fictitious_w;  ///< g_wi g_io,true: the fictitious target o_i (with truth)
  /// Each RunnerSettings::compare_estimators' estimate, once it has one.
  std::vector<std::optional<SE3>> compare_w;
};

struct FrameRecord {
  int frame = 0;
  double t = 0.0;
  std::vector<CameraRecord> cameras;
  std::optional<SE3> central_w;  ///< centralized average of the detecting cameras' PnP poses
  std::optional<SE3> g_star;     ///< average of the detecting cameras' fictitious poses (truth)
  std::optional<SE3> g_wo_true;  ///< true target pose (truth)
  std::optional<obs::Energies> energies;        ///< networked, against g_star
  std::optional<obs::Energies> energies_indep;  ///< independent observers (initialised ones)
  std::optional<obs::EpsLevels> eps;            ///< networked, Definition 1 at this frame
  /// Each compared estimator's energies against g_star, when every camera has an estimate.
  std::vector<std::optional<obs::Energies>> energies_compare;
};

/// Completes a frame's record from its cameras' records (delta, initialized, est_w, indep_w,
/// pnp_w, fictitious_w) and g_wo_true: the centralized average, g*, the energies and the
/// epsilon-levels. The in-process runner and the merge of per-camera processes both use it.
void evaluate_frame(FrameRecord& r);

/// The observer settings of one camera of a run: its networked estimator (k_s = settings.k_s,
/// initialised from PnP and from its neighbours under InitMode::Pnp) or its independent
/// baseline (the paper's observer with k_s = 0, initialised from PnP only).
obs::ObserverSettings camera_observer_settings(const RunnerSettings& s, bool independent);

/// h times the estimator's rate bound (vmo: h (k_e + 2 k_s d_max)) for `substeps` sub-steps of a
/// frame of dt: < 2 stable, <= 1 non-oscillating.
double step_factor(const obs::ObserverSettings& s, double dt, int substeps, int max_degree);

class Runner {
 public:
  /// g_wi: believed camera poses (the source of g_ij). Throws std::invalid_argument on a
  /// disconnected graph.
  Runner(const obs::Graph& graph, std::vector<SE3> g_wi, RunnerSettings settings);

  /// Processes frame `frame` (time t): initialises cameras, advances the networked observer and
  /// the independent observers by dt with this frame's measurements, evaluates, and returns the
  /// record of the estimates after the frame.
  const FrameRecord& process(int frame, double t, double dt,
                             const std::vector<obs::Measurement>& in,
                             const std::optional<SE3>& g_wo_true = std::nullopt);
  /// process() in two halves, for cameras on their own clocks: advance() initialises cameras
  /// and steps every observer by dt with these (held) measurements; record() evaluates the
  /// current estimates as frame `frame` at time t (in: delta, PnP and true g_io at that time)
  /// and appends the record to history().
  void advance(double dt, const std::vector<obs::Measurement>& in);
  const FrameRecord& record(int frame, double t, const std::vector<obs::Measurement>& in,
                            const std::optional<SE3>& g_wo_true = std::nullopt);

  const std::vector<FrameRecord>& history() const { return history_; }
  /// Camera i's networked estimate in the world now (g_wi g_bar_i), once it has one.
  std::optional<SE3> estimate_world(size_t i) const;
  int substeps(double dt) const { return net_.substeps(dt); }
  const RunnerSettings& settings() const { return settings_; }
  const obs::Graph& graph() const { return graph_; }
  const std::vector<SE3>& camera_poses() const { return g_wi_; }
  /// h times the estimator's rate bound for a frame of dt: < 2 stable, <= 1 non-oscillating.
  double step_factor(double dt) const;
  /// Moving cameras: believed poses g_wi and body velocities V_wi = [v; w] for the coming frame
  /// (the -hat(V_wi) g_bar term of (eq:EsRRBM) and g_ij = g_wi^-1 g_wj). Call before process().
  void set_camera_motion(const std::vector<SE3>& g_wi, const std::vector<obs::Vec6>& V_wi);
  /// Replaces the in-process exchange of the networked observer.
  void set_transport(std::unique_ptr<obs::Transport> t) { net_.set_transport(std::move(t)); }

 private:
  std::vector<obs::NetworkedObserver*> observers();  ///< networked, independent, compared

  obs::Graph graph_;
  std::vector<SE3> g_wi_;
  RunnerSettings settings_;
  obs::NetworkedObserver net_;
  obs::NetworkedObserver indep_;
  std::vector<obs::NetworkedObserver> compare_;
  std::vector<FrameRecord> history_;
};

}  // namespace netvmo::run
