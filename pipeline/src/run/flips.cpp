#include "netvmo/pipeline/run/flips.hpp"

#include <algorithm>
#include <cmath>

namespace netvmo::run {

namespace {
double step_deg(const obs::SE3& a, const obs::SE3& b) {
  return obs::log_so3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}
}  // namespace

FlipCount count_flips(const std::vector<std::optional<obs::SE3>>& poses, double threshold_deg) {
  FlipCount c;
  for (size_t k = 1; k < poses.size(); ++k) {
    if (!poses[k - 1] || !poses[k]) continue;
    ++c.pairs;
    c.flips += step_deg(*poses[k - 1], *poses[k]) > threshold_deg;
  }
  return c;
}

double max_step_deg(const std::vector<std::optional<obs::SE3>>& poses) {
  double m = 0.0;
  for (size_t k = 1; k < poses.size(); ++k)
    if (poses[k - 1] && poses[k]) m = std::max(m, step_deg(*poses[k - 1], *poses[k]));
  return m;
}

}  // namespace netvmo::run
