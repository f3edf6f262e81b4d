// The estimator a camera runs: what it does with its measurement and its neighbours' messages in
// one exchange round. Two are registered:
//   vmo          the paper's networked visual motion observer, (eq:EsRRBM) with (eq:input_f-);
//   zero-offset  proportional-integral dynamic average consensus on the visible cameras'
//                measured world-frame poses, whose ratio is g* of (eq:g_ave) without offset.
//
// Every estimator is one class in its own file under observer/src/estimators/ and one line in
// the registry's table (observer/src/estimators/registry.cpp). The command line's choices and
// help, the simulation, the image runner and the sweep all read that table. An estimator is
// stateless: a camera's state (EstimatorState) lives in its CameraObserver, so the same unit runs
// in process, in a process of its own and on a camera's own clock.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/measurement.hpp"

namespace netvmo::obs {

struct ObserverSettings;
struct EstimateMessage;

/// The largest consensus state an estimator publishes per round (doubles), the fixed size of
/// EstimateMessage::state: zero-offset's x_i and eta_i, 13 values each.
constexpr int kConsensusStateSize = 26;
using ConsensusState = std::array<double, kConsensusStateSize>;

/// One camera's state that its estimator advances (owned by its CameraObserver).
struct EstimatorState {
  SE3 g_bar = SE3::Identity();     ///< the estimate g_bar_i in the camera's frame
  bool initialized = true;         ///< the estimate exists (see CameraObserver::set_initialized)
  Vec6 u = Vec6::Zero();           ///< vmo: the last input u_ei (diagnostics)
  ConsensusState consensus{};      ///< zero-offset: x_i (13) then eta_i (13), published each round
  bool consensus_started = false;  ///< zero-offset: x_i(0) = r_i(0) has been set
  bool holding = true;             ///< zero-offset: the output is held (x_delta,i < threshold)
  SE3 held_w = SE3::Identity();    ///< zero-offset: the estimate in the world frame
};

/// What an estimator reads of its camera in a step (read-only).
struct EstimatorContext {
  const ObserverSettings& settings;
  const ErrorModel& model;
  const SE3& g_wi;       ///< believed camera pose
  const Vec6& V_wi;      ///< camera body velocity
  const Measurement& z;  ///< the held measurement
  /// The latest accepted message of each neighbour (CameraObserver::latest()).
  const std::vector<std::optional<EstimateMessage>>& latest;
  int network_size;  ///< n, or 0 when unknown
};

/// What an estimator reads of its camera when a measurement arrives (read-only): not the
/// neighbours' messages.
struct MeasurementContext {
  const ObserverSettings& settings;
  const ErrorModel& model;
  const Measurement& z;  ///< the new measurement, held until the next one
};

class Estimator {
 public:
  virtual ~Estimator() = default;
  /// The name used on the command line, in scenario files and in summaries.
  virtual std::string_view name() const = 0;
  /// One line for --help.
  virtual std::string_view description() const = 0;
  /// Doubles of EstimateMessage::state this estimator publishes and reads (0 for vmo).
  virtual int state_size() const = 0;
  /// Throws std::invalid_argument when the estimator cannot run with these settings, naming why.
  virtual void check(const ObserverSettings& s, const ErrorModel& model, int network_size) const;
  /// An upper bound on the spectral radius of the linearised dynamics for any graph of largest
  /// degree d_max: sub-steps h with h * rate_bound <= 1 are stable and non-oscillating for the
  /// forward-Euler discretisation (docs/observer.md, "Discretisation and stability").
  virtual double rate_bound(const ObserverSettings& s, int max_degree) const = 0;
  /// A new measurement (cx.z) arrived; it is held until the next one.
  virtual void measured(const MeasurementContext& cx, EstimatorState& st) const = 0;
  /// Advances the state by h with the held measurement and the neighbours' latest messages.
  /// Throws std::domain_error from the error model.
  virtual void step(const EstimatorContext& cx, EstimatorState& st, double h) const = 0;
};

/// The registry (registry.hpp): every estimator, in the order help texts list them (the default
/// first); estimators().find(name) throws std::invalid_argument naming the known ones.
const Registry<Estimator>& estimators();

}  // namespace netvmo::obs
