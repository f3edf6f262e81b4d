// The networked visual motion observer under imperfect visibility.
//
// Model (eq:EsRRBM):  d/dt g_bar_i = -hat(V_wi) g_bar_i + g_bar_i hat(u_ei)
// Input (eq:input_f-): u_ei = delta_i k_e e_ei + k_s sum_{j in N_i} E_R(g_bar_i^-1 g_ij g_bar_j)
//
// g_bar_i is camera i's estimate of the average target pose g*_i = g_wi^-1 g*, in its own frame.
// The visual error e_ei is either reconstructed from image features, e = J^dagger(g_bar) f_e
// (eq:eei), or taken from a pose, e = E_R(g_bar^-1 g_io) (eq:ER), where g_io is the true
// (fictitious) relative pose in simulation or a per-camera PnP pose on images.
//
// Discretisation. Frames arrive every dt; the measurement is held over the frame (zero-order
// hold) and the ODE is integrated with N sub-steps of the Lie-group Euler scheme
//     g_bar_i <- exp(-h hat(V_wi)) g_bar_i exp(h hat(u_ei)),   h = dt / N,
// all cameras using the estimates of the previous sub-step (one exchange round per sub-step).
// Stability: with the exact error model the world-frame positions obey the linear system
//     d/dt p = -(k_e Delta + k_s L) p + k_e Delta p_o
// and the rotations the same system to first order, so the scheme is a forward-Euler step of it.
// Gershgorin gives lambda_max(k_e Delta + k_s L) <= k_e + 2 k_s d_max (d_max = largest degree),
// so h (k_e + 2 k_s d_max) < 2 is stable and h (k_e + 2 k_s d_max) <= 1 is stable and
// non-oscillating. By default N is the smallest count with h (k_e + 2 k_s d_max) <= step_factor
// (= 1): k_e = 1, k_s = 50, d_max = 3 at 30 frames/s gives N = 11.
#pragma once

#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/jacobian.hpp"
#include "netvmo/observer/lie.hpp"

namespace netvmo::obs {

/// How the visual feedback term e_ei is obtained.
enum class VisualError {
  Pose,     ///< e = E_R(g_bar^-1 g_io) from a measured relative pose (exact / PnP)
  Features  ///< e = J^dagger(g_bar) (f - f_bar(g_bar)) from image features (eq:eei)
};

/// One camera's visual input for one frame.
struct VisualMeasurement {
  bool visible = false;          ///< delta_i(t) of (eq:input_f-)
  SE3 g_io = SE3::Identity();    ///< measured relative pose (VisualError::Pose)
  Eigen::VectorXd f;             ///< measured features, 2m (VisualError::Features)
};

struct ObserverSettings {
  double k_e = 1.0;          ///< visual feedback gain k_e > 0
  double k_s = 50.0;         ///< mutual feedback gain k_s >= 0 (0: independent observers)
  VisualError error = VisualError::Pose;
  FeatureModel features = FeatureModel::square(0.2);  ///< used by VisualError::Features
  double step_factor = 1.0;  ///< c in h (k_e + 2 k_s d_max) <= c; c < 2 is required
  int substeps = 0;          ///< sub-steps (exchange rounds) per frame; 0 = from step_factor
};

/// Visual error term e_ei for the current estimate.
/// Throws std::domain_error for the feature model if g_bar puts a feature behind the camera.
Vec6 visual_error(const SE3& g_bar, const VisualMeasurement& z, const ObserverSettings& s);

/// E_R(g_bar_i^-1 g_bar_{i,j}) with both poses expressed in the world frame through the believed
/// camera poses: g_bar_i^-1 g_ij g_bar_j = (g_wi g_bar_i)^-1 (g_wj g_bar_j).
Vec6 mutual_error(const SE3& g_bar_w_i, const SE3& g_bar_w_j);

/// One Lie-group Euler step of (eq:EsRRBM): exp(-h hat(V_wi)) g_bar exp(h hat(u)).
SE3 integrate(const SE3& g_bar, const Vec6& V_wi, const Vec6& u, double h);

/// Smallest N with (dt/N) (k_e + 2 k_s d_max) <= step_factor.
int stable_substeps(double dt, const ObserverSettings& s, int max_degree);

/// How estimates travel between cameras in one exchange round. Implementations must fill
/// inbox[i][k] with the estimate camera i received from graph.neighbors(i)[k], given what every
/// camera published (its estimate in the world frame, g_wi g_bar_i). A transport may deliver a
/// stale value (e.g. the last one received) when a message is lost.
class Transport {
 public:
  virtual ~Transport() = default;
  virtual void exchange(const Graph& graph, const std::vector<SE3>& published,
                        std::vector<std::vector<SE3>>& inbox) = 0;
};

/// Direct in-process delivery (the default).
class InProcessTransport final : public Transport {
 public:
  void exchange(const Graph& graph, const std::vector<SE3>& published,
                std::vector<std::vector<SE3>>& inbox) override;
};

/// All cameras' observers, exchanging estimates through a Transport (in process by default).
class NetworkedObserver {
 public:
  /// Throws std::invalid_argument if the graph is disconnected (Assumption 1) or a gain is
  /// negative.
  NetworkedObserver(Graph graph, ObserverSettings settings);

  int size() const { return graph_.size(); }
  const Graph& graph() const { return graph_; }
  const ObserverSettings& settings() const { return settings_; }

  /// Initial estimates g_bar_i(0), each in its camera's frame.
  void reset(const std::vector<SE3>& g_bar);
  /// Believed camera poses g_wi (the source of g_ij = g_wi^-1 g_wj). Default: identity.
  void set_camera_poses(const std::vector<SE3>& g_wi);
  /// Camera body velocities V_wi = [v; w] (the -hat(V_wi) g_bar term). Default: zero.
  void set_camera_velocities(const std::vector<Vec6>& V_wi);

  /// Cameras that take part: an inactive camera keeps its estimate and its neighbours leave it
  /// out of their mutual term (used while a camera has no initial estimate yet). Default: all.
  void set_active(const std::vector<bool>& active);
  const std::vector<bool>& active() const { return active_; }
  /// Replaces the in-process exchange (the transport must outlive the observer).
  void set_transport(Transport* transport) { transport_ = transport; }

  /// Sub-steps used for a frame of length dt.
  int substeps(double dt) const;
  /// Advances all estimates by dt with z held over the frame; z.size() == size().
  void step(double dt, const std::vector<VisualMeasurement>& z);

  const std::vector<SE3>& estimates() const { return g_bar_; }
  /// g_bar_w,i = g_wi g_bar_i: each camera's estimate in the world frame.
  std::vector<SE3> estimates_world() const;
  /// The last inputs u_ei applied (useful for diagnostics).
  const std::vector<Vec6>& inputs() const { return u_; }

 private:
  Graph graph_;
  ObserverSettings settings_;
  std::vector<SE3> g_bar_;
  std::vector<SE3> g_wi_;
  std::vector<Vec6> V_wi_;
  std::vector<Vec6> u_;
  std::vector<bool> active_;
  std::vector<SE3> published_;
  std::vector<std::vector<SE3>> inbox_;
  InProcessTransport in_process_;
  Transport* transport_ = nullptr;  // nullptr: in_process_ (keeps the object copyable)
};

}  // namespace netvmo::obs
