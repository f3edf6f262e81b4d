// vmo: the paper's networked visual motion observer. One Lie-group Euler step of
//   (eq:EsRRBM)   d/dt g_bar_i = -hat(V_wi) g_bar_i + g_bar_i hat(u_ei)
//   (eq:input_f-) u_ei = delta_i k_e e_ei + k_s sum_{j in N_i} E_R(g_bar_i^-1 g_ij g_bar_j),
// with the camera's self-initialisation (ObserverSettings::init_from_*).
#include <algorithm>

#include "../pose_kernel.hpp"
#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/estimator.hpp"

namespace netvmo::obs::estimator_kinds {
namespace {

// Smallest depth of the target's feature points under an estimate (camera frame).
double min_depth(const SE3& g_bar, const FeatureModel& m) {
  double z = 1e300;
  for (const auto& p : m.points_o) z = std::min(z, (g_bar * p).z());
  return z;
}

class Vmo final : public Estimator {
 public:
  std::string_view name() const override { return "vmo"; }
  std::string_view description() const override {
    return "the paper's networked visual motion observer (steady state O(k_e/k_s) from g*)";
  }
  int state_size() const override { return 0; }
  double rate_bound(const ObserverSettings& s, int max_degree) const override {
    return s.k_e + 2.0 * s.k_s * max_degree;  // Gershgorin on k_e Delta + k_s L
  }

  void measured(const MeasurementContext& cx, EstimatorState& st) const override {
    const auto& s = cx.settings;
    const auto& z = cx.z;
    if (!s.init_from_measurement || !z.delta || !z.g_io_pnp) return;
    // An estimate of the image-feature model must keep the tag in front of the camera.
    const bool unusable = st.initialized && cx.model.input() == MeasurementInput::features &&
                          min_depth(st.g_bar, s.features) < s.min_feature_depth;
    if (!st.initialized || unusable) {
      st.g_bar = *z.g_io_pnp;
      st.initialized = true;
    }
  }

  void step(const EstimatorContext& cx, EstimatorState& st, double h) const override {
    const auto& s = cx.settings;
    if (!st.initialized && s.init_from_neighbours) {
      std::vector<SE3> nb;
      for (const auto& m : cx.latest)
        if (m && m->initialized) nb.push_back(m->g_w);
      if (!nb.empty()) {
        st.g_bar = kernel::start_from_neighbours(cx.g_wi, nb);
        st.initialized = true;
      }
    }
    if (!st.initialized) return;
    // The same arithmetic as NetworkedObserver's in-process fast path (pose_kernel.hpp).
    const kernel::Pose own_w = kernel::compose(kernel::pose_of(cx.g_wi), kernel::pose_of(st.g_bar));
    kernel::PoseSum nb;
    for (const auto& m : cx.latest)
      if (m && m->initialized) nb.add(kernel::pose_of(m->g_w));
    const Vec6 mutual = kernel::mutual_sum(own_w, nb);  // sum_j E_R(g_bar_i^-1 g_ij g_bar_j)
    Vec6 visual;
    const bool sees = cx.model.usable(cx.z);
    if (sees) visual = cx.model.error(st.g_bar, cx.z, s.features);
    st.u = kernel::vmo_input(s, mutual, sees ? &visual : nullptr);  // (eq:input_f-)
    st.g_bar = kernel::to_se3(kernel::integrate(kernel::pose_of(st.g_bar), cx.V_wi, st.u, h));
  }
};

}  // namespace

const Estimator& vmo() {
  static const Vmo e;
  return e;
}

}  // namespace netvmo::obs::estimator_kinds
