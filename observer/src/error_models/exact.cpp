// exact: e_ei = E_R(g_bar_i^-1 g_io_i) (eq:ER) with the true (fictitious) relative pose, the
// quantity the paper's analysis uses. Simulation and rendered data only.
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
    return E_R(g_bar.inverse(Eigen::Isometry) * *z.g_io_true);  // e_ei = E_R(g_ei), (eq:ER)
  }
};
}  // namespace

const ErrorModel& exact() {
  static const Exact model;
  return model;
}
}  // namespace netvmo::obs::models
