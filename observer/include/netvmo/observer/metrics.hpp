// The paper's averaging metrics: the SE(3) mean g* (eq:g_ave), the estimation error energies
// U_p and U_R (eq:energy), the spreads rho_p, rho_R and the achieved epsilon-levels of
// Definition 1 (defn:averaging).
//
// All quantities are computed in the world frame. They equal the paper's camera-frame forms
// because g*_i = g_wi^-1 g* and g_bar_i = g_wi^-1 g_bar_w,i share the same g_wi, which cancels:
// ||p_bar_i - p*_i|| = ||p_bar_w,i - p*|| and phi(R*_i^T R_bar_i) = phi(R*^T R_bar_w,i).
#pragma once

#include <optional>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::obs {

/// g* = argmin_g sum_j psi(g^-1 g_j) (eq:g_ave). Since psi(g^-1 g_j) = 1/2 |p_j - p|^2 +
/// tr(I - R^T R_j), p* is the mean position and R* maximises tr(R^T sum_j R_j): the projection
/// of the summed rotations onto SO(3) (SVD). Throws std::invalid_argument on an empty set.
SE3 average_pose(const std::vector<SE3>& g);

struct Energies {
  double U_p = 0.0;  ///< 1/2 sum_i |p_bar_w,i - p*|^2 (Section 5)
  double U_R = 0.0;  ///< sum_i phi(R*^T R_bar_w,i) (eq:energy)
};
Energies energies(const std::vector<SE3>& g_bar_w, const SE3& g_star);

struct Spread {
  double rho_p = 0.0;  ///< sum_{i in V_f} |p_wo_i - p*|^2
  double rho_R = 0.0;  ///< sum_{i in V_f} phi(R*^T R_wo_i)
  double phi_m = 0.0;  ///< max_{i in V_f} phi(R*^T R_wo_i) (Lemma 1)
};
/// Spread of the visible cameras' fictitious target poses g_wo_i about g*.
Spread spread(const std::vector<SE3>& g_wo_visible, const SE3& g_star);

struct EpsLevels {
  double eps_p = 0.0;  ///< (1/n sum_i |p_bar_i - p*_i|^2) / (rho_p / |V_f|)
  double eps_R = 0.0;  ///< (1/n sum_i phi(R*_i^T R_bar_i)) / (rho_R / |V_f|)
};
/// The smallest epsilon for which the current estimates lie in Omega_p(eps), Omega_R(eps)
/// (Definition 1), up to the boundary. Infinite when rho is zero and the error is not.
EpsLevels eps_levels(const std::vector<SE3>& g_bar_w, const SE3& g_star, const Spread& s,
                     int n_visible);

/// The orientation offset of Theorem 1 as k -> 0 and epsilon -> 0: eps_R -> 1 - beta with
/// beta = 1 - sqrt(2 zeta), zeta > phi_m; returns the infimum sqrt(2 phi_m) (valid when < 1).
double theorem1_orientation_offset(const Spread& s);

/// Theorem 1's guarantee for a gain ratio k = k_e/k_s, as its proof (Appendix) bounds it with
/// zeta -> phi_m and the position level epsilon -> 0: with beta = 1 - sqrt(2 phi_m),
///   eps_R <= (sqrt(k diam |V_f| / (2 beta)) + sqrt(1 - (sqrt(beta) - sqrt(k W))^2))^2,
/// and, by the same argument with beta = 1 (the paper: "the position part in the same way"),
///   eps_p <= (sqrt(k diam |V_f| / 2) + sqrt(1 - (1 - sqrt(k W))^2))^2.
/// Infinite where the proof gives no bound (k W >= beta, resp. k W >= 1). As k -> 0 eps_R tends
/// to 1 - beta = theorem1_orientation_offset(s) and eps_p to 0.
struct Theorem1Bound {
  double eps_p = 0.0;
  double eps_R = 0.0;
};
Theorem1Bound theorem1_bound(double k, const Spread& s, double W, int diameter, int n_visible);

/// How far camera i's neighbours' estimates lie from its own, as a covariance (the one netvmo
/// publishes with a camera's estimate, docs/ros2.md): (1/m) sum_j d_j d_j^T over the m
/// neighbours' latest world-frame estimates g_j, d_j = [p_j - p_i; log(R_j R_i^T)] (position,
/// then rotation about the world axes: ROS's PoseWithCovariance order in the world frame). It is
/// the consensus disagreement that the mutual term of (eq:input_f-) drives to zero, not an
/// accuracy against the true target pose. nullopt when there is no neighbour estimate.
std::optional<Eigen::Matrix<double, 6, 6>> neighbour_spread(const SE3& own_w,
                                                            const std::vector<SE3>& neighbours_w);

}  // namespace netvmo::obs
