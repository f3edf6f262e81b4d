// pnp: e_ei = E_R(g_bar_i^-1 g_io,PnP) (eq:ER) with the camera's own pose measurement. Its
// equilibrium is the exact model's, applied to measured poses.
#include "../pose_kernel.hpp"
#include "netvmo/observer/error_model.hpp"

namespace netvmo::obs::models {
namespace {
class Pnp final : public ErrorModel {
 public:
  std::string_view name() const override { return "pnp"; }
  std::string_view description() const override {
    return "e = E_R(g_bar^-1 g_io,PnP) with the camera's own PnP pose";
  }
  MeasurementInput input() const override { return MeasurementInput::pnp_pose; }
  Vec6 error(const SE3& g_bar, const Measurement& z, const FeatureModel&) const override {
    // E_R(g_bar^-1 g_io,PnP) (eq:ER), the bits of the Isometry expression (pose_kernel.hpp)
    return kernel::pose_error(kernel::pose_of(g_bar), kernel::pose_of(*z.g_io_pnp));
  }
  const SE3* measured_pose(const Measurement& z) const override {
    return z.g_io_pnp ? &*z.g_io_pnp : nullptr;
  }
};
}  // namespace

const ErrorModel& pnp() {
  static const Pnp model;
  return model;
}
}  // namespace netvmo::obs::models
