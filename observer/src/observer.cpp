#include "netvmo/observer/observer.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace netvmo::obs {

Vec6 visual_error(const SE3& g_bar, const VisualMeasurement& z, const ObserverSettings& s) {
  if (s.error == VisualError::Features) return reconstruct_error(g_bar, z.f, s.features);  // (eq:eei)
  return E_R(g_bar.inverse(Eigen::Isometry) * z.g_io);  // e_ei = E_R(g_ei), (eq:ER)
}

Vec6 mutual_error(const SE3& g_bar_w_i, const SE3& g_bar_w_j) {
  // E_R(A^-1 B) = [R_A^T (p_B - p_A); e_R(R_A^T R_B)] without forming the product.
  const Mat3 Rt = g_bar_w_i.linear().transpose();
  Vec6 e;
  e.head<3>() = Rt * (g_bar_w_j.translation() - g_bar_w_i.translation());
  e.tail<3>() = e_R(Rt * g_bar_w_j.linear());
  return e;
}

SE3 integrate(const SE3& g_bar, const Vec6& V_wi, const Vec6& u, double h) {
  SE3 g = g_bar * exp_se3(h * u);
  if (!V_wi.isZero(0.0)) g = exp_se3(-h * V_wi) * g;
  // Re-orthonormalise against round-off drift over long runs (cheap: unit quaternion).
  g.linear() = Eigen::Quaterniond(g.linear()).normalized().toRotationMatrix();
  return g;
}

int stable_substeps(double dt, const ObserverSettings& s, int max_degree) {
  const double lambda_max = s.k_e + 2.0 * s.k_s * max_degree;
  return std::max(1, static_cast<int>(std::ceil(dt * lambda_max / s.step_factor - 1e-12)));
}

void InProcessTransport::exchange(const Graph& graph, const std::vector<SE3>& published,
                                  std::vector<std::vector<SE3>>& inbox) {
  for (int i = 0; i < graph.size(); ++i) {
    auto& box = inbox[static_cast<size_t>(i)];
    const auto& nb = graph.neighbors(i);
    for (size_t k = 0; k < nb.size(); ++k) box[k] = published[static_cast<size_t>(nb[k])];
  }
}

NetworkedObserver::NetworkedObserver(Graph graph, ObserverSettings settings)
    : graph_(std::move(graph)), settings_(std::move(settings)) {
  if (!graph_.connected())
    throw std::invalid_argument("communication graph is disconnected (Assumption 1); components: " +
                                describe_components(graph_.components(), {}));
  if (!(settings_.k_e >= 0.0) || !(settings_.k_s >= 0.0))
    throw std::invalid_argument("gains k_e and k_s must be non-negative");
  if (!(settings_.step_factor > 0.0 && settings_.step_factor < 2.0))
    throw std::invalid_argument("step_factor must lie in (0, 2)");
  const auto n = static_cast<size_t>(graph_.size());
  g_bar_.assign(n, SE3::Identity());
  g_wi_.assign(n, SE3::Identity());
  V_wi_.assign(n, Vec6::Zero());
  u_.assign(n, Vec6::Zero());
  active_.assign(n, true);
  published_.assign(n, SE3::Identity());
  inbox_.resize(n);
  for (size_t i = 0; i < n; ++i)
    inbox_[i].assign(static_cast<size_t>(graph_.degree(static_cast<int>(i))), SE3::Identity());
}

void NetworkedObserver::set_active(const std::vector<bool>& active) {
  if (active.size() != active_.size()) throw std::invalid_argument("active mask: wrong count");
  active_ = active;
}

void NetworkedObserver::reset(const std::vector<SE3>& g_bar) {
  if (g_bar.size() != g_bar_.size()) throw std::invalid_argument("reset: wrong number of estimates");
  g_bar_ = g_bar;
}

void NetworkedObserver::set_camera_poses(const std::vector<SE3>& g_wi) {
  if (g_wi.size() != g_wi_.size()) throw std::invalid_argument("camera poses: wrong count");
  g_wi_ = g_wi;
}

void NetworkedObserver::set_camera_velocities(const std::vector<Vec6>& V_wi) {
  if (V_wi.size() != V_wi_.size()) throw std::invalid_argument("camera velocities: wrong count");
  V_wi_ = V_wi;
}

int NetworkedObserver::substeps(double dt) const {
  return settings_.substeps > 0 ? settings_.substeps
                                : stable_substeps(dt, settings_, graph_.max_degree());
}

void NetworkedObserver::step(double dt, const std::vector<VisualMeasurement>& z) {
  if (z.size() != g_bar_.size()) throw std::invalid_argument("step: wrong number of measurements");
  const int N = substeps(dt);
  const double h = dt / N;
  const int n = graph_.size();
  for (int k = 0; k < N; ++k) {
    // One exchange round: every camera publishes its estimate in the world frame,
    // g_wi g_bar_i, so that g_bar_i^-1 g_ij g_bar_j = (g_wi g_bar_i)^-1 (g_wj g_bar_j).
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<size_t>(i);
      published_[si] = g_wi_[si] * g_bar_[si];
    }
    (transport_ ? *transport_ : static_cast<Transport&>(in_process_)).exchange(graph_, published_, inbox_);
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<size_t>(i);
      if (!active_[si]) continue;
      Vec6 mutual = Vec6::Zero();
      const auto& nb = graph_.neighbors(i);
      for (size_t m = 0; m < nb.size(); ++m)
        if (active_[static_cast<size_t>(nb[m])]) mutual += mutual_error(published_[si], inbox_[si][m]);
      Vec6 u = settings_.k_s * mutual;  // (eq:input_f-)
      if (z[si].visible) u += settings_.k_e * visual_error(g_bar_[si], z[si], settings_);
      u_[si] = u;
    }
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<size_t>(i);
      if (active_[si]) g_bar_[si] = integrate(g_bar_[si], V_wi_[si], u_[si], h);  // (eq:EsRRBM)
    }
  }
}

std::vector<SE3> NetworkedObserver::estimates_world() const {
  std::vector<SE3> out(g_bar_.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = g_wi_[i] * g_bar_[i];
  return out;
}

}  // namespace netvmo::obs
