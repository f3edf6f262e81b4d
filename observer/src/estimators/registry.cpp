// The estimator registry. Adding an estimator: a new file in this folder that defines a function
// returning it, and one line in the table below (with its declaration).
#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/estimator.hpp"

namespace netvmo::obs {

namespace estimator_kinds {
const Estimator& vmo();          // vmo.cpp
const Estimator& zero_offset();  // zero_offset.cpp
}  // namespace estimator_kinds

const Registry<Estimator>& estimators() {
  static const Registry<Estimator> table{"estimator",
                                         {
                                             &estimator_kinds::vmo(),
                                             &estimator_kinds::zero_offset(),
                                         }};
  return table;
}

void Estimator::check(const ObserverSettings&, const ErrorModel&, int) const {}

}  // namespace netvmo::obs
