// The error-model registry. Adding a model: a new file in this folder that defines a function
// returning it, and one line in the table below (with its declaration).
#include <stdexcept>

#include "netvmo/observer/error_model.hpp"

namespace netvmo::obs {

namespace models {
const ErrorModel& exact();     // exact.cpp
const ErrorModel& jacobian();  // jacobian.cpp
const ErrorModel& pnp();       // pnp.cpp
}  // namespace models

const std::vector<const ErrorModel*>& error_models() {
  static const std::vector<const ErrorModel*> table{
      &models::exact(),
      &models::jacobian(),
      &models::pnp(),
  };
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

std::string error_model_names() {
  std::string s;
  for (const auto* m : error_models()) s += (s.empty() ? "" : ", ") + std::string(m->name());
  return s;
}

const ErrorModel& find_error_model(std::string_view name) {
  for (const auto* m : error_models())
    if (m->name() == name) return *m;
  throw std::invalid_argument("unknown error model '" + std::string(name) + "' (" +
                              error_model_names() + ")");
}

}  // namespace netvmo::obs
