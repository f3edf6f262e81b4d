// zero-offset: g* of (eq:g_ave) without the vmo's O(k_e/k_s) offset, by proportional-integral
// dynamic average consensus (Freeman, Yang & Lynch, CDC 2006; in the form of Kia, Van Scoy,
// Cortes, Freeman, Lynch & Martinez, "Tutorial on dynamic average consensus", IEEE Control
// Systems Magazine 2019).
//
// Camera i's input is r_i = delta_i [p_wo,i; vec(R_wo,i); 1] in R^13, where g_wo,i = g_wi g_io,i
// is its fictitious target: the measured relative pose (the error model's field: the true one
// for `exact`, PnP for `pnp`) seen through its believed pose. With a_ij the graph's adjacency,
// alpha = k_e > 0 and beta = k_s >= 0,
//   dx_i/dt   = -alpha (x_i - r_i) - beta sum_j a_ij (x_i - x_j) - sum_j a_ij (eta_i - eta_j)
//   deta_i/dt =  alpha beta sum_j a_ij (x_i - x_j).
// For constant inputs on a connected graph every x_i converges to the average (1/n) sum_j r_j
// from any initial x, eta (proof in docs/observer.md, "The zero-offset estimator"). The estimate is
// the ratio of the first 12 components to the 13th, x_delta,i -> |V_f|/n:
//   p_bar_w,i = x_p,i / x_delta,i -> (1/|V_f|) sum_{j in V_f} p_wo,j = p*,
//   R_bar_w,i = proj_SO(3)(x_R,i)  -> proj_SO(3)(sum_{j in V_f} R_wo,j) = R*  (eq:g_ave),
// the projection being invariant to the positive factor x_delta,i. While x_delta,i is below the
// hold threshold (default 1/(2n): no camera sees the target) the last estimate is held in the
// world frame. Each round a camera publishes [x_i; eta_i], 26 doubles.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/estimator.hpp"

namespace netvmo::obs::estimator_kinds {
namespace {

constexpr int kDim = 13;  // [p (3); R row-major (9); delta]
using Vec13 = Eigen::Matrix<double, kDim, 1>;

// r_i = delta_i [p_wo,i; vec(R_wo,i); 1] with g_wo,i = g_wi g_io,i.
Vec13 input(const EstimatorContext& cx) {
  Vec13 r = Vec13::Zero();
  if (!cx.model.usable(cx.z)) return r;
  const SE3& g_io =
      cx.model.input() == MeasurementInput::true_pose ? *cx.z.g_io_true : *cx.z.g_io_pnp;
  const SE3 g_wo = cx.g_wi * g_io;
  r.head<3>() = g_wo.translation();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) r(3 + 3 * a + b) = g_wo.linear()(a, b);
  r(12) = 1.0;
  return r;
}

class ZeroOffset final : public Estimator {
 public:
  std::string_view name() const override { return "zero-offset"; }
  std::string_view description() const override {
    return "PI dynamic average consensus on the visible cameras' measured poses: exactly g*";
  }
  int state_size() const override { return 2 * kDim; }

  void check(const ObserverSettings& s, const ErrorModel& model, int n) const override {
    if (model.input() == MeasurementInput::features)
      throw std::invalid_argument(
          "the zero-offset estimator averages measured poses; the '" + std::string(model.name()) +
          "' error model gives image features (use an error model that reads a pose)");
    if (!(s.k_e > 0.0)) throw std::invalid_argument("the zero-offset estimator needs k_e > 0");
    if (!(s.hold_threshold > 0.0) && n <= 0)
      throw std::invalid_argument(
          "the zero-offset estimator needs the network size (or a hold threshold)");
  }

  // In the Laplacian's eigenbasis (eigenvalue lambda) each pair (x, eta) follows
  // s^2 + (alpha + beta lambda) s + alpha beta lambda^2 = 0. Real roots lie in
  // [-(alpha + beta lambda), 0); complex ones have |1 + h s|^2 = 1 - h (alpha + beta lambda) +
  // h^2 alpha beta lambda^2, below 1 when h alpha lambda <= 1. With lambda <= 2 d_max
  // (Gershgorin), h max(alpha + 2 beta d_max, 2 alpha d_max) <= 1 is stable.
  double rate_bound(const ObserverSettings& s, int max_degree) const override {
    return std::max(s.k_e + 2.0 * s.k_s * max_degree, 2.0 * s.k_e * max_degree);
  }

  void measured(const MeasurementContext&, EstimatorState&) const override {}

  void step(const EstimatorContext& cx, EstimatorState& st, double h) const override {
    const auto& s = cx.settings;
    const Vec13 r = input(cx);
    Eigen::Map<Vec13> x(st.consensus.data()), eta(st.consensus.data() + kDim);
    if (!st.consensus_started) {  // x_i(0) = r_i(0), eta_i(0) = 0: any start converges
      x = r;
      eta.setZero();
      st.held_w = cx.g_wi * st.g_bar;
      st.consensus_started = true;
    }
    Vec13 dx = Vec13::Zero(), deta = Vec13::Zero();
    for (const auto& m : cx.latest) {
      if (!m) continue;
      dx += x - Eigen::Map<const Vec13>(m->state.data());
      deta += eta - Eigen::Map<const Vec13>(m->state.data() + kDim);
    }
    const double alpha = s.k_e, beta = s.k_s;
    const Vec13 x_dot = -alpha * (x - r) - beta * dx - deta;
    eta += h * alpha * beta * dx;
    x += h * x_dot;

    const double threshold =
        s.hold_threshold > 0.0 ? s.hold_threshold : 0.5 / static_cast<double>(cx.network_size);
    st.holding = !(x(12) >= threshold);
    if (!st.holding) {
      Mat3 M;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) M(a, b) = x(3 + 3 * a + b);
      st.held_w.translation() = x.head<3>() / x(12);
      st.held_w.linear() = project_to_so3(M);  // R* of (eq:g_ave), up to the factor x_delta
      st.initialized = true;
    }
    if (st.initialized) st.g_bar = cx.g_wi.inverse() * st.held_w;
  }
};

}  // namespace

const Estimator& zero_offset() {
  static const ZeroOffset e;
  return e;
}

}  // namespace netvmo::obs::estimator_kinds
