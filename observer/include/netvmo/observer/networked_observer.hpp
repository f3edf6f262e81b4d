// The networked visual motion observer under imperfect visibility, in one process: n
// CameraObservers (camera_observer.hpp) exchanging their estimates through a Transport.
//
// Discretisation. Frames arrive every dt; the measurement is held over the frame (zero-order
// hold) and the ODE is integrated with N sub-steps of the Lie-group Euler scheme
//     g_bar_i <- exp(-h hat(V_wi)) g_bar_i exp(h hat(u_ei)),   h = dt / N,
// and each moving camera's believed pose with it, g_wi <- g_wi exp(h hat(V_wi)),
// all cameras using the estimates of the previous sub-step (one exchange round per sub-step).
// Stability: with the exact error model the world-frame positions obey the linear system
//     d/dt p = -(k_e Delta + k_s L) p + k_e Delta p_o
// and the rotations the same system to first order, so the scheme is a forward-Euler step of it.
// Gershgorin gives lambda_max(k_e Delta + k_s L) <= k_e + 2 k_s d_max (d_max = largest degree),
// so h (k_e + 2 k_s d_max) < 2 is stable and h (k_e + 2 k_s d_max) <= 1 is stable and
// non-oscillating. By default N is the smallest count with h (k_e + 2 k_s d_max) <= step_factor
// (= 1): k_e = 1, k_s = 50, d_max = 3 at 30 frames/s gives N = 11.
//
// Cost and threads. A sub-step is O(n + |E|). With the in-process exchange and the vmo
// estimator the rounds run on compact arrays (observer/src/in_process_vmo.hpp): every camera
// reads its neighbours' estimates of the previous round from a double buffer, steps and writes its
// next one, the same arithmetic as CameraObserver::step, and the cameras' state is written back at
// the end of the frame. Otherwise (another estimator, another transport) each sub-step is an
// exchange round of exchange.hpp, the same one a camera's own process runs: every camera sends
// through the transport, then takes in what reached it, on the calling thread, then steps. The
// steps run over ObserverSettings::threads threads (a contiguous part of the cameras each, what a
// thread has not reached taken by one through with its own, each camera writing only its own
// state), so the results are bit-identical for any thread count.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/transport.hpp"
#include "netvmo/observer/worker_pool.hpp"

namespace netvmo::obs {

class InProcessVmo;

class NetworkedObserver {
 public:
  /// Throws std::invalid_argument if the graph is disconnected (Assumption 1), a gain is
  /// negative or the error model is unknown. Exchanges in process until set_transport().
  NetworkedObserver(Graph graph, ObserverSettings settings);
  ~NetworkedObserver();
  NetworkedObserver(NetworkedObserver&&) noexcept;
  NetworkedObserver& operator=(NetworkedObserver&&) noexcept;

  int size() const { return graph_.size(); }
  const Graph& graph() const { return graph_; }
  const ObserverSettings& settings() const { return settings_; }
  /// Camera i's observer. (Mutable access makes the next frame re-check the cameras' stored
  /// messages before it takes the in-process fast path.)
  CameraObserver& camera(int i) {
    stored_known_ = false;
    return cameras_[static_cast<size_t>(i)];
  }
  const CameraObserver& camera(int i) const { return cameras_[static_cast<size_t>(i)]; }

  /// Initial estimates g_bar_i(0), each in its camera's frame.
  void reset(const std::vector<SE3>& g_bar);
  /// Believed camera poses g_wi (the source of g_ij = g_wi^-1 g_wj). Default: identity.
  void set_camera_poses(const std::vector<SE3>& g_wi);
  /// Camera body velocities V_wi = [v; w] (the -hat(V_wi) g_bar term; step() also moves the
  /// believed poses on with them). Default: zero.
  void set_camera_velocities(const std::vector<Vec6>& V_wi);
  /// Cameras that take part (CameraObserver::set_initialized). Default: all.
  void set_active(const std::vector<bool>& active);
  std::vector<bool> active() const;
  /// Replaces the in-process exchange (an InProcessTransport of the same graph keeps the fast
  /// path).
  void set_transport(std::unique_ptr<Transport> transport);
  /// Threads that run the per-camera steps (1: the calling thread only).
  int threads() const;

  /// Sub-steps used for a frame of length dt.
  int substeps(double dt) const;
  /// Advances all estimates by dt with z held over the frame; z.size() == size(). When a camera
  /// throws (the error model's std::domain_error) the exception of the smallest camera index
  /// is rethrown after the sub-step; the estimates are then unspecified.
  void step(double dt, const std::vector<Measurement>& z);

  std::vector<SE3> estimates() const;
  /// g_bar_w,i = g_wi g_bar_i: each camera's estimate in the world frame.
  std::vector<SE3> estimates_world() const;
  /// The last inputs u_ei applied (diagnostics).
  std::vector<Vec6> inputs() const;

 private:
  void check_count(size_t count, const char* what) const;
  /// One exchange round of every camera (exchange.hpp) and a step of h.
  void exchange_round(double h);
  /// f(i) for every camera i, on the pool's threads when there is one.
  void for_each_camera(const std::function<void(int)>& f);

  Graph graph_;
  ObserverSettings settings_;
  std::vector<CameraObserver> cameras_;
  std::unique_ptr<Transport> transport_;  ///< default: an InProcessTransport of graph_
  /// transport_ delivers directly over graph_ (an InProcessTransport of it): the fast path may
  /// run the frame's rounds instead.
  bool direct_ = true;
  std::vector<EstimateMessage> inbox_;  ///< scratch of take_estimates
  std::unique_ptr<WorkerPool> pool_;    ///< null: every step on the calling thread
  /// The in-process exchange of the vmo estimator on compact arrays (null: another estimator).
  std::unique_ptr<InProcessVmo> fast_;
  /// The cameras' stored messages are the fast path's own (none can make a new one out of order).
  bool stored_known_ = false;
};

}  // namespace netvmo::obs
