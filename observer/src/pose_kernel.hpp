// The vmo's per-camera arithmetic on compact poses (a 3x3 rotation and a translation, no 4x4
// matrices), shared by CameraObserver's step (through the vmo estimator) and the in-process fast
// path of NetworkedObserver (in_process_vmo.hpp), so that both compute the same bits. Every
// expression is the one the SE3 (Eigen::Isometry3d) code evaluated before: Isometry products are
// the 3x3 products below, so results are unchanged to the last bit.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/metrics.hpp"

namespace netvmo::obs::kernel {

/// A rigid transform g = [R p; 0 1] stored as 12 doubles.
struct Pose {
  Mat3 R;
  Vec3 p;
};

inline Pose pose_of(const SE3& g) {
  return {g.linear(), g.translation()};
}

inline SE3 to_se3(const Pose& g) {
  SE3 s = SE3::Identity();
  s.linear() = g.R;
  s.translation() = g.p;
  return s;
}

/// a b, as the Isometry product: [R_a R_b, R_a p_b + p_a].
inline Pose compose(const Pose& a, const Pose& b) {
  return {a.R * b.R, a.R * b.p + a.p};
}

/// E_R(g_i^-1 g_j) for two world-frame estimates (eq:input_f-), without forming the product:
/// [R_i^T (p_j - p_i); e_R(R_i^T R_j)], e_R = sk(.)^vee (eq:ER). Only the six off-diagonal
/// entries of R_i^T R_j are formed, each summed in the order in which Eigen's 3x3 products
/// (Mat3 * Mat3, Mat3 * Vec3) sum it: ((x0 + x1) + x2) in rows 0 and 1, (x0 + (x1 + x2)) in row
/// 2, so that the result is that of the Eigen expression to the last bit (a test checks it).
inline Vec6 mutual_error(const Pose& i, const Pose& j) {
  const Mat3& A = i.R;  // R_i^T(r, k) = A(k, r)
  const Mat3& B = j.R;
  const double d0 = j.p(0) - i.p(0), d1 = j.p(1) - i.p(1), d2 = j.p(2) - i.p(2);
  // (R_i^T M)(r, c) = sum_k A(k, r) M(k, c); rows 0, 1 and row 2 of the product.
  const auto top = [&A](int r, double m0, double m1, double m2) {
    return (A(0, r) * m0 + A(1, r) * m1) + A(2, r) * m2;
  };
  const auto bottom = [&A](double m0, double m1, double m2) {
    return A(0, 2) * m0 + (A(1, 2) * m1 + A(2, 2) * m2);
  };
  Vec6 e;
  e(0) = top(0, d0, d1, d2);
  e(1) = top(1, d0, d1, d2);
  e(2) = bottom(d0, d1, d2);
  const double s01 = top(0, B(0, 1), B(1, 1), B(2, 1));
  const double s02 = top(0, B(0, 2), B(1, 2), B(2, 2));
  const double s10 = top(1, B(0, 0), B(1, 0), B(2, 0));
  const double s12 = top(1, B(0, 2), B(1, 2), B(2, 2));
  const double s20 = bottom(B(0, 0), B(1, 0), B(2, 0));
  const double s21 = bottom(B(0, 1), B(1, 1), B(2, 1));
  // vee(S) = [S(2,1) - S(1,2), S(0,2) - S(2,0), S(1,0) - S(0,1)] / 2 (lie.hpp)
  e(3) = (s21 - s12) * 0.5;
  e(4) = (s02 - s20) * 0.5;
  e(5) = (s10 - s01) * 0.5;
  return e;
}

/// One Lie-group Euler step of (eq:EsRRBM): exp(-h hat(V_wi)) g_bar exp(h hat(u)), the rotation
/// then re-orthonormalised through a unit quaternion (round-off drift over long runs).
inline Pose integrate(const Pose& g_bar, const Vec6& V_wi, const Vec6& u, double h) {
  Pose e;
  exp_se3(h * u, e.R, e.p);
  Pose g = compose(g_bar, e);
  if (!V_wi.isZero(0.0)) {
    Pose m;
    exp_se3(-h * V_wi, m.R, m.p);
    g = compose(m, g);
  }
  g.R = Eigen::Quaterniond(g.R).normalized().toRotationMatrix();
  return g;
}

/// The pose part of CameraObserver::receive's check: finite, |R^T R - I| <= 1e-6 entrywise (the
/// Gram matrix is symmetric: six entries) and det R > 0.
inline MessageVerdict check_pose(const Pose& g) {
  if (!g.R.allFinite() || !g.p.allFinite()) return MessageVerdict::not_finite;
  const Mat3& R = g.R;
  double worst = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      const double gram = R(0, a) * R(0, b) + R(1, a) * R(1, b) + R(2, a) * R(2, b);
      worst = std::max(worst, std::abs(gram - (a == b ? 1.0 : 0.0)));
    }
  if (!(worst <= 1e-6) || !(R.determinant() > 0.0)) return MessageVerdict::not_a_rotation;
  return MessageVerdict::accepted;
}

/// init_from_neighbours: g_bar_i = g_wi^-1 average_pose(g_wj g_bar_j) over the initialised
/// neighbours' latest estimates nb (not empty).
inline SE3 start_from_neighbours(const SE3& g_wi, const std::vector<SE3>& nb) {
  return g_wi.inverse() * average_pose(nb);
}

/// u_ei of (eq:input_f-) from the summed mutual term and the visual error (null: not visible).
inline Vec6 vmo_input(const ObserverSettings& s, const Vec6& mutual, const Vec6* visual) {
  Vec6 u = s.k_s * mutual;
  if (visual) u += s.k_e * *visual;
  return u;
}

}  // namespace netvmo::obs::kernel
