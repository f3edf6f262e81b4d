// One camera's networked estimator: the unit of the paper's distributed estimator (and of the
// zero-offset estimator, estimator.hpp). Camera i owns exactly
//   - its estimate g_bar_i of g*_i = g_wi^-1 g* (in its own frame),
//   - its believed pose g_wi and body velocity V_wi (the -hat(V_wi) g_bar_i term),
//   - its latest measurement (delta_i, features or a pose), held until the next one,
//   - the latest estimate each neighbour j in N_i published, g_wj g_bar_j,
// and advances by an elapsed time h with one step of its estimator (estimator.hpp); the paper's
// (`vmo`, the default) is one Lie-group Euler step of
//   (eq:EsRRBM)   d/dt g_bar_i = -hat(V_wi) g_bar_i + g_bar_i hat(u_ei)
//   (eq:input_f-) u_ei = delta_i k_e e_ei + k_s sum_{j in N_i} E_R(g_bar_i^-1 g_ij g_bar_j).
// The same class runs in process (NetworkedObserver composes n of them with a Transport), in a
// process of its own (one per camera, exchanging messages over a middleware), or on a camera's
// own clock: only who calls publish(), receive() and step() changes.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/estimate_message.hpp"
#include "netvmo/observer/estimator.hpp"
#include "netvmo/observer/jacobian.hpp"
#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/measurement.hpp"
#include "netvmo/observer/observer_settings.hpp"

namespace netvmo::obs {

/// E_R(g_bar_i^-1 g_bar_{i,j}) with both poses expressed in the world frame through the believed
/// camera poses: g_bar_i^-1 g_ij g_bar_j = (g_wi g_bar_i)^-1 (g_wj g_bar_j) (eq:input_f-).
Vec6 mutual_error(const SE3& g_bar_w_i, const SE3& g_bar_w_j);
/// The summed mutual term sum_j E_R(g_bar_w_i^-1 g_bar_w_j) of (eq:input_f-) over the estimates
/// g_bar_w_nb, as the vmo computes it (one 3x3 product: E_R is linear in g_bar_w_j's entries);
/// the sum of the mutual_error terms up to round-off.
Vec6 mutual_sum(const SE3& g_bar_w_i, const std::vector<SE3>& g_bar_w_nb);

/// One Lie-group Euler step of (eq:EsRRBM): exp(-h hat(V_wi)) g_bar exp(h hat(u)), the rotation
/// re-orthonormalised through a unit quaternion.
SE3 integrate(const SE3& g_bar, const Vec6& V_wi, const Vec6& u, double h);

class InProcessVmo;

class CameraObserver {
 public:
  /// `index`: this camera's index in the network (the sender of its messages); `neighbours`:
  /// N_i as indices; `network_size`: n (0 = unknown; zero-offset needs it unless
  /// hold_threshold is set). Throws std::invalid_argument on a negative gain, a step factor
  /// outside (0, 2), an unknown error model or estimator, settings the estimator cannot run
  /// with, or a neighbour list that contains `index` or repeats.
  CameraObserver(int index, std::vector<int> neighbours, ObserverSettings settings,
                 int network_size = 0);

  int index() const { return index_; }
  const std::vector<int>& neighbours() const { return neighbours_; }
  const ObserverSettings& settings() const { return settings_; }
  const ErrorModel& error_model() const { return *model_; }
  const Estimator& estimator() const { return *estimator_; }
  /// This camera's incarnation, carried by its messages (default 0).
  void set_incarnation(std::uint64_t k) { incarnation_ = k; }

  /// Sets g_bar_i (in the camera's frame). Does not change initialized().
  void reset(const SE3& g_bar) { st_.g_bar = g_bar; }
  /// An uninitialised camera keeps its estimate, and its neighbours leave it out of their
  /// mutual term (used while a camera has no estimate yet). Default: initialised.
  void set_initialized(bool on) { st_.initialized = on; }
  bool initialized() const { return st_.initialized; }
  /// Believed camera pose g_wi (the source of g_ij = g_wi^-1 g_wj). Default: identity.
  void set_camera_pose(const SE3& g_wi) { g_wi_ = g_wi; }
  const SE3& camera_pose() const { return g_wi_; }
  /// Camera body velocity V_wi = [v; w]. Default: zero. step(h) also moves the believed pose
  /// on, g_wi <- g_wi exp(h hat(V_wi)), so that set_camera_pose(g_k) with
  /// V_wi = log(g_k^-1 g_k+1) / (t_k+1 - t_k) lands exactly on g_k+1 at the end of the frame.
  void set_camera_velocity(const Vec6& V_wi) { V_wi_ = V_wi; }
  /// The measurement used by step() until the next call (zero-order hold); with
  /// init_from_measurement it may (re-)initialise the estimate from the PnP pose.
  void set_measurement(const Measurement& z);
  const Measurement& measurement() const { return z_; }

  /// This round's message: the estimate in the world frame, g_wi g_bar_i. Advances the round.
  EstimateMessage publish(double stamp = 0.0);
  /// The same message written into `out`, whose consensus state beyond the estimator's
  /// state_size() is left as it is (zero in a message that only this camera writes).
  void publish(EstimateMessage& out, double stamp = 0.0);
  /// Stores a neighbour's message as its latest estimate, after checking it (MessageVerdict).
  MessageVerdict receive(const EstimateMessage& m);
  /// Forgets neighbour j's estimate (e.g. silent past a staleness bound): it leaves the mutual
  /// term until it is heard again. No effect when j is not a neighbour.
  void forget(int j);
  /// The latest accepted message of each neighbour, in neighbours() order (empty if none), its
  /// consensus state kept as far as the estimator reads it (state_size(); the rest zero). (After
  /// a frame of NetworkedObserver's in-process fast path the messages are written when first
  /// read: call latest() again after a step rather than keeping the reference.)
  const std::vector<std::optional<EstimateMessage>>& latest() const { return latest_.get(); }
  /// Messages refused so far, by verdict (index = MessageVerdict value).
  const std::vector<std::uint64_t>& refused() const { return refused_; }

  /// Advances g_bar_i by h with the held measurement and the latest neighbour estimates (one
  /// step of the estimator; vmo: with init_from_neighbours an uninitialised camera first tries
  /// to start from its neighbours, and nothing happens while uninitialised). Throws
  /// std::domain_error from the error model.
  void step(double h);

  const SE3& estimate() const { return st_.g_bar; }
  /// g_bar_w,i = g_wi g_bar_i: the estimate in the world frame.
  SE3 estimate_world() const { return g_wi_ * st_.g_bar; }
  /// The input u_ei of the last step (vmo, diagnostics).
  const Vec6& input() const { return st_.u; }
  /// The estimator's whole state (consensus state, hold flag).
  const EstimatorState& state() const { return st_; }

 private:
  int index_;
  std::vector<int> neighbours_;
  ObserverSettings settings_;
  const ErrorModel* model_;
  const Estimator* estimator_;
  int network_size_ = 0;
  EstimatorState st_;
  SE3 g_wi_ = SE3::Identity();
  Vec6 V_wi_ = Vec6::Zero();
  Measurement z_;
  std::uint64_t round_ = 0;
  std::uint64_t incarnation_ = 0;
  /// The neighbours' messages (latest()). NetworkedObserver's in-process fast path leaves them
  /// in its own buffers at the end of a frame, and they are written from there when first read
  /// (most frames nobody reads them; at 10,000 cameras writing 40,000 messages every frame took
  /// a tenth of it). Reading, copying and moving write them first; concurrent reads are safe.
  class NeighbourMessages {
   public:
    using Slots = std::vector<std::optional<EstimateMessage>>;
    NeighbourMessages() = default;
    NeighbourMessages(const NeighbourMessages& o) : slots_(o.get()) {}
    NeighbourMessages(NeighbourMessages&& o) noexcept : slots_(std::move(o.get())) {}
    NeighbourMessages& operator=(const NeighbourMessages& o);
    NeighbourMessages& operator=(NeighbourMessages&& o) noexcept;
    ~NeighbourMessages() = default;
    const Slots& get() const {
      if (state_.load(std::memory_order_acquire) != kWritten) write();
      return slots_;
    }
    Slots& get() {
      std::as_const(*this).get();
      return slots_;
    }
    /// From now on the slots are the fast path's messages to its camera at `position`
    /// (InProcessVmo::fill), until read.
    void defer(const InProcessVmo* source, int position);

   private:
    void write() const;
    enum State : int { kWritten, kDeferred, kWriting };
    mutable Slots slots_;
    const InProcessVmo* source_ = nullptr;
    int position_ = -1;
    mutable std::atomic<int> state_{kWritten};
  };
  NeighbourMessages latest_;
  std::vector<std::uint64_t> refused_;

  /// NetworkedObserver's in-process fast path reads and writes back this state directly.
  friend class InProcessVmo;

  EstimatorContext context() const {
    return {settings_, *model_, g_wi_, V_wi_, z_, latest_.get(), network_size_};
  }
};

}  // namespace netvmo::obs
