// exact: e_ei = E_R(g_bar_i^-1 g_io_i) (eq:ER) with the true (fictitious) relative pose, the
// quantity the paper's analysis uses. Simulation and rendered data only.
#include "../pose_kernel.hpp"
#include "netvmo/observer/error_model.hpp"

namespace netvmo::obs::models {
namespace {
class Exact final : public ErrorModel {
 public:
  std::string_view name() const override { return "exact"; }
  std::string_view description() const override {
    return "e = E_R(g_bar^-1 g_io) with the true relative pose (simulation, rendered data)";
  }
  MeasurementInput input() const override { return MeasurementInput::true_pose; }
  Vec6 error(const SE3& g_bar, const Measurement& z, const FeatureModel&) const override {
    // e_ei = E_R(g_bar^-1 g_io) (eq:ER), the bits of the Isometry expression (pose_kernel.hpp)
    return kernel::pose_error(kernel::pose_of(g_bar), kernel::pose_of(*z.g_io_true));
  }
  const SE3* measured_pose(const Measurement& z) const override {
    return z.g_io_true ? &*z.g_io_true : nullptr;
  }
};
}  // namespace

const ErrorModel& exact() {
  static const Exact model;
  return model;
}
}  // namespace netvmo::obs::models
