// The estimator registry. Adding an estimator: a new file in this folder that defines a function
// returning it, and one line in the table below (with its declaration).
#include <stdexcept>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/estimator.hpp"

namespace netvmo::obs {

namespace estimator_kinds {
const Estimator& vmo();          // vmo.cpp
const Estimator& zero_offset();  // zero_offset.cpp
}  // namespace estimator_kinds

const std::vector<const Estimator*>& estimators() {
  static const std::vector<const Estimator*> table{
      &estimator_kinds::vmo(),
      &estimator_kinds::zero_offset(),
  };
  return table;
}

void Estimator::check(const ObserverSettings&, const ErrorModel&, int) const {}

std::string estimator_names() {
  std::string s;
  for (const auto* e : estimators()) s += (s.empty() ? "" : ", ") + std::string(e->name());
  return s;
}

const Estimator& find_estimator(std::string_view name) {
  for (const auto* e : estimators())
    if (e->name() == name) return *e;
  throw std::invalid_argument("unknown estimator '" + std::string(name) + "' (" +
                              estimator_names() + ")");
}

}  // namespace netvmo::obs
