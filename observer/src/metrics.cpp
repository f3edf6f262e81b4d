#include "netvmo/observer/metrics.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace netvmo::obs {

SE3 average_pose(const std::vector<SE3>& g) {
  if (g.empty()) throw std::invalid_argument("average_pose of an empty set");
  Vec3 p = Vec3::Zero();
  Mat3 M = Mat3::Zero();
  for (const auto& gj : g) {
    p += gj.translation();
    M += gj.linear();
  }
  SE3 out = SE3::Identity();
  out.translation() = p / static_cast<double>(g.size());
  out.linear() = project_to_so3(M);  // (eq:g_ave)
  return out;
}

Energies energies(const std::vector<SE3>& g_bar_w, const SE3& g_star) {
  Energies e;
  const Mat3 Rt = g_star.linear().transpose();
  for (const auto& g : g_bar_w) {
    e.U_p += 0.5 * (g.translation() - g_star.translation()).squaredNorm();
    e.U_R += phi(Rt * g.linear());  // (eq:energy)
  }
  return e;
}

Spread spread(const std::vector<SE3>& g_wo_visible, const SE3& g_star) {
  Spread s;
  const Mat3 Rt = g_star.linear().transpose();
  for (const auto& g : g_wo_visible) {
    s.rho_p += (g.translation() - g_star.translation()).squaredNorm();
    const double ph = phi(Rt * g.linear());
    s.rho_R += ph;
    s.phi_m = std::max(s.phi_m, ph);
  }
  return s;
}

EpsLevels eps_levels(const std::vector<SE3>& g_bar_w, const SE3& g_star, const Spread& s,
                     int n_visible) {
  const Energies e = energies(g_bar_w, g_star);
  const double n = static_cast<double>(g_bar_w.size());
  const double ep = 2.0 * e.U_p / n;  // 1/n sum |p_bar - p*|^2
  const double eR = e.U_R / n;
  const auto ratio = [](double num, double den) {
    if (den > 0.0) return num / den;
    return num > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
  };
  return EpsLevels{ratio(ep, s.rho_p / n_visible), ratio(eR, s.rho_R / n_visible)};
}

double theorem1_orientation_offset(const Spread& s) {
  return std::sqrt(2.0 * s.phi_m);
}

Theorem1Bound theorem1_bound(double k, const Spread& s, double W, int diameter, int n_visible) {
  const double inf = std::numeric_limits<double>::infinity();
  // (sqrt(alpha |V_f| / rho) + sqrt(eps'))^2 with alpha = k rho diam / (2 beta) and
  // eps' = 1 - (sqrt(beta) - sqrt(k W))^2 (Appendix, eps -> 0).
  const auto bound = [&](double beta) {
    if (!(beta > 0.0) || !(k * W < beta)) return inf;
    const double a = std::sqrt(k * diameter * n_visible / (2.0 * beta));
    const double b = std::sqrt(beta) - std::sqrt(k * W);
    return std::pow(a + std::sqrt(1.0 - b * b), 2);
  };
  return {bound(1.0), bound(1.0 - std::sqrt(2.0 * s.phi_m))};
}

std::optional<Eigen::Matrix<double, 6, 6>> neighbour_spread(const SE3& own_w,
                                                            const std::vector<SE3>& neighbours_w) {
  if (neighbours_w.empty()) return std::nullopt;
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  for (const SE3& g : neighbours_w) {
    Vec6 d;
    d.head<3>() = g.translation() - own_w.translation();
    d.tail<3>() = log_so3(g.linear() * own_w.linear().transpose());
    C += d * d.transpose();
  }
  return C / static_cast<double>(neighbours_w.size());
}

}  // namespace netvmo::obs
