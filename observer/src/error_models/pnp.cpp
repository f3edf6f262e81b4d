// pnp: e_ei = E_R(g_bar_i^-1 g_io,PnP) (eq:ER) with the camera's own pose measurement. Its
// equilibrium is the exact model's, applied to measured poses.
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
    return E_R(g_bar.inverse(Eigen::Isometry) * *z.g_io_pnp);  // (eq:ER)
  }
};
}  // namespace

const ErrorModel& pnp() {
  static const Pnp model;
  return model;
}
}  // namespace netvmo::obs::models
