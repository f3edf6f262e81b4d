#include "netvmo/observer/observer_settings.hpp"

#include <algorithm>
#include <cmath>

#include "netvmo/observer/estimator.hpp"

namespace netvmo::obs {

int frame_substeps(double dt, const ObserverSettings& s, int max_degree) {
  return s.substeps > 0 ? s.substeps : stable_substeps(dt, s, max_degree);
}

int stable_substeps(double dt, const ObserverSettings& s, int max_degree) {
  const double lambda_max = estimators().find(s.estimator).rate_bound(s, max_degree);
  return std::max(1, static_cast<int>(std::ceil(dt * lambda_max / s.step_factor - 1e-12)));
}

}  // namespace netvmo::obs
