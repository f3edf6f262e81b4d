// The observer's settings: gains, discretisation, self-initialisation and threads, shared by every
// camera of a network (CameraObserver, NetworkedObserver) and by the estimators that read them.
#pragma once

#include <string>

#include "netvmo/observer/jacobian.hpp"

namespace netvmo::obs {

/// Gains and discretisation of the observer. Defaults are the paper's Section 5 gains.
struct ObserverSettings {
  /// The estimator, by its registry name (estimator.hpp): vmo (the paper's) or zero-offset.
  std::string estimator = "vmo";
  double k_e = 1.0;   ///< visual feedback gain k_e > 0 (zero-offset: alpha, the input gain)
  double k_s = 50.0;  ///< mutual feedback gain k_s >= 0 (0: independent; zero-offset: beta)
  /// Visual error model, by its registry name (error_model.hpp): exact, jacobian or pnp.
  std::string error_model = "exact";
  FeatureModel features = FeatureModel::square(0.2);  ///< the target's feature points
  double step_factor = 1.0;  ///< c in h (k_e + 2 k_s d_max) <= c; c < 2 is required
  int substeps = 0;          ///< sub-steps (exchange rounds) per frame; 0 = from step_factor
  /// Self-initialisation, the same in process and in a camera's own process. An uninitialised
  /// camera that sees the target (delta and a PnP pose in set_measurement) starts from its own
  /// PnP pose; with the image-feature model an initialised estimate whose tag corner comes
  /// closer to the camera plane than min_feature_depth is re-initialised the same way.
  bool init_from_measurement = false;
  /// An uninitialised camera starts, at the beginning of a step (after the round's messages are
  /// in), from the average of its initialised neighbours' latest estimates mapped into its frame:
  /// g_bar_i = g_wi^-1 average_pose(g_wj g_bar_j).
  bool init_from_neighbours = false;
  double min_feature_depth = 0.05;  ///< [m], see init_from_measurement
  /// zero-offset: the output is held while the camera's estimate x_delta,i of the fraction of
  /// cameras that see the target is below this; 0 = 1/(2n), half the smallest non-zero fraction.
  double hold_threshold = 0.0;
  /// NetworkedObserver: threads that run the per-camera steps, the calling thread included;
  /// 0 = one per core (std::thread::hardware_concurrency()). Results are bit-identical for any
  /// count. A network uses at most one thread per kCamerasPerThread cameras (below that a
  /// sub-step's synchronisation costs more than the thread saves).
  int threads = 0;
};

/// The fewest cameras per thread of NetworkedObserver (ObserverSettings::threads).
constexpr int kCamerasPerThread = 256;

/// Smallest N with (dt/N) * rate_bound <= step_factor, rate_bound the estimator's
/// (vmo: k_e + 2 k_s d_max).
int stable_substeps(double dt, const ObserverSettings& s, int max_degree);
/// Sub-steps (exchange rounds) of a frame of length dt: s.substeps when set, else
/// stable_substeps(dt, s, max_degree).
int frame_substeps(double dt, const ObserverSettings& s, int max_degree);

}  // namespace netvmo::obs
