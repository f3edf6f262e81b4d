// jacobian: e_ei = J^dagger(g_bar_i) (f_i - f_bar_i) (eq:eei), the error reconstructed from the
// image features through the image Jacobian, as the paper's observer does. The points are the
// measurement's own (Measurement::points_o, a tag bundle) when it has them, else the model's.
#include "netvmo/observer/error_model.hpp"

namespace netvmo::obs::models {
namespace {
class Jacobian final : public ErrorModel {
 public:
  std::string_view name() const override { return "jacobian"; }
  std::string_view description() const override {
    return "e = J^+(g_bar) (f - f_bar) from the image features (the tag's corners)";
  }
  MeasurementInput input() const override { return MeasurementInput::features; }
  Vec6 error(const SE3& g_bar, const Measurement& z, const FeatureModel& model) const override {
    if (z.points_o.empty()) return reconstruct_error(g_bar, z.f, model);  // (eq:eei)
    // This frame's points (a bundle's seen tags): J stacked over every one of them, (eq:eei).
    return reconstruct_error(g_bar, z.f, FeatureModel{z.points_o, model.lambda});
  }
};
}  // namespace

const ErrorModel& jacobian() {
  static const Jacobian model;
  return model;
}
}  // namespace netvmo::obs::models
