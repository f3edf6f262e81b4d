// The error-model registry. Adding a model: a new file in this folder that defines a function
// returning it, and one line in the table below (with its declaration).
#include "netvmo/observer/error_model.hpp"

namespace netvmo::obs {

namespace models {
const ErrorModel& exact();     // exact.cpp
const ErrorModel& jacobian();  // jacobian.cpp
const ErrorModel& pnp();       // pnp.cpp
}  // namespace models

const Registry<ErrorModel>& error_models() {
  static const Registry<ErrorModel> table{"error model",
                                          {
                                              &models::exact(),
                                              &models::jacobian(),
                                              &models::pnp(),
                                          }};
  return table;
}

bool ErrorModel::usable(const Measurement& z) const {
  if (!z.delta) return false;
  switch (input()) {
    case MeasurementInput::features:
      return z.f.size() > 0;
    case MeasurementInput::pnp_pose:
      return z.g_io_pnp.has_value();
    case MeasurementInput::true_pose:
      return z.g_io_true.has_value();
  }
  return false;
}

}  // namespace netvmo::obs
