// The vmo's per-camera arithmetic on compact poses (a 3x3 rotation and a translation, no 4x4
// matrices), shared by CameraObserver's step (through the vmo estimator) and the in-process fast
// path of NetworkedObserver (in_process_vmo.hpp), so that both compute the same bits. The single
// mutual term and the products are the SE3 (Eigen::Isometry3d) expressions to the last bit; the
// summed mutual term, the exponential (lie.cpp) and the quaternion re-orthonormalisation are
// cheaper forms of the same mathematics, equal to the plain expressions up to round-off (tests
// CameraObserver.StepArithmeticIsThePlainExpressionsToRoundOff).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "netvmo/observer/estimate_message.hpp"
#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/observer_settings.hpp"

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

// R_i^T M for 3x3 rotations and vectors, each entry summed in the order in which Eigen's 3x3
// products (Mat3 * Mat3, Mat3 * Vec3, also on the blocks of an Isometry's 4x4 matrix) sum it:
// ((x0 + x1) + x2) in rows 0 and 1, (x0 + (x1 + x2)) in row 2, so that the errors below are those
// of the Eigen expressions to the last bit (tests check it). A(k, r) = R_i^T(r, k).
struct TransposedProduct {
  const Mat3& A;
  double top(int r, double m0, double m1, double m2) const {  // rows 0 and 1
    return (A(0, r) * m0 + A(1, r) * m1) + A(2, r) * m2;
  }
  double bottom(double m0, double m1, double m2) const {  // row 2
    return A(0, 2) * m0 + (A(1, 2) * m1 + A(2, 2) * m2);
  }
  double row(int r, const Vec3& m) const {
    return r < 2 ? top(r, m(0), m(1), m(2)) : bottom(m(0), m(1), m(2));
  }
  /// e_R(R_i^T B) = vee(sk(R_i^T B)) (eq:ER): only the six off-diagonal entries of the product.
  Vec3 rotation_error(const Mat3& B) const {
    const double s01 = top(0, B(0, 1), B(1, 1), B(2, 1));
    const double s02 = top(0, B(0, 2), B(1, 2), B(2, 2));
    const double s10 = top(1, B(0, 0), B(1, 0), B(2, 0));
    const double s12 = top(1, B(0, 2), B(1, 2), B(2, 2));
    const double s20 = bottom(B(0, 0), B(1, 0), B(2, 0));
    const double s21 = bottom(B(0, 1), B(1, 1), B(2, 1));
    // vee(S) = [S(2,1) - S(1,2), S(0,2) - S(2,0), S(1,0) - S(0,1)] / 2 (lie.hpp)
    return {(s21 - s12) * 0.5, (s02 - s20) * 0.5, (s10 - s01) * 0.5};
  }
};

/// E_R(g_i^-1 g_j) for two world-frame estimates (eq:input_f-), without forming the product:
/// [R_i^T (p_j - p_i); e_R(R_i^T R_j)], e_R = sk(.)^vee (eq:ER); the bits of that Eigen
/// expression (Mat3 R_i^T times R_j and times p_j - p_i).
inline Vec6 mutual_error(const Pose& i, const Pose& j) {
  const TransposedProduct Rt{i.R};
  const Vec3 d(j.p(0) - i.p(0), j.p(1) - i.p(1), j.p(2) - i.p(2));
  Vec6 e;
  for (int r = 0; r < 3; ++r) e(r) = Rt.row(r, d);
  e.tail<3>() = Rt.rotation_error(j.R);
  return e;
}

/// The visual error of the pose error models, E_R(g_bar^-1 g) (eq:ER) for a measured relative
/// pose g (exact: g_io_i, pnp: g_io,PnP), without forming the product: the bits of the Isometry
/// expression E_R(g_bar.inverse(Eigen::Isometry) * g), whose translation is R^T p_g + (-R^T p).
inline Vec6 pose_error(const Pose& g_bar, const Pose& g) {
  const TransposedProduct Rt{g_bar.R};
  Vec6 e;
  for (int r = 0; r < 3; ++r) e(r) = Rt.row(r, g.p) - Rt.row(r, g_bar.p);
  e.tail<3>() = Rt.rotation_error(g.R);
  return e;
}

/// The initialised neighbours' world-frame estimates of a round, summed entry by entry in
/// neighbour order, for mutual_sum.
struct PoseSum {
  Mat3 R = Mat3::Zero();
  Vec3 p = Vec3::Zero();
  int count = 0;
  void add(const Pose& g) {
    R += g.R;
    p += g.p;
    ++count;
  }
};

/// The mutual term sum_{j in N_i} E_R(g_i^-1 g_j) of (eq:input_f-) from the neighbours' summed
/// estimates: E_R (eq:ER) is linear in g_j's entries, [R_i^T (p_j - p_i); vee(sk(R_i^T R_j))],
/// so the sum is [R_i^T (sum_j p_j - m p_i); vee(sk(R_i^T sum_j R_j))] over the m neighbours:
/// one 3x3 product instead of one per neighbour. Equal to the sum of mutual_error terms up to
/// round-off (a few units in the last place of the summands; a test bounds it).
inline Vec6 mutual_sum(const Pose& i, const PoseSum& nb) {
  if (nb.count == 0) return Vec6::Zero();
  const Mat3& A = i.R;  // R_i^T(r, k) = A(k, r)
  const Mat3& B = nb.R;
  const double m = nb.count;
  const Vec3 d = nb.p - m * i.p;
  const auto dot = [&A](int r, double x0, double x1, double x2) {  // row r of R_i^T times x
    return A(0, r) * x0 + A(1, r) * x1 + A(2, r) * x2;
  };
  Vec6 e;
  e(0) = dot(0, d(0), d(1), d(2));
  e(1) = dot(1, d(0), d(1), d(2));
  e(2) = dot(2, d(0), d(1), d(2));
  // vee(S) = [S(2,1) - S(1,2), S(0,2) - S(2,0), S(1,0) - S(0,1)] / 2 (lie.hpp), S = R_i^T B
  e(3) = (dot(2, B(0, 1), B(1, 1), B(2, 1)) - dot(1, B(0, 2), B(1, 2), B(2, 2))) * 0.5;
  e(4) = (dot(0, B(0, 2), B(1, 2), B(2, 2)) - dot(2, B(0, 0), B(1, 0), B(2, 0))) * 0.5;
  e(5) = (dot(1, B(0, 0), B(1, 0), B(2, 0)) - dot(0, B(0, 1), B(1, 1), B(2, 1))) * 0.5;
  return e;
}

inline bool finite(const Pose& g) {
  return g.R.allFinite() && g.p.allFinite();
}

/// R re-orthonormalised through its unit quaternion: Eigen's Quaternion(R).normalized()
/// .toRotationMatrix() (Shoemake's conversion, branch for branch) with the quaternion left
/// unnormalised: the conversion's q times 2t, t = sqrt(t^2), needs no square root, and the
/// rotation of q / |q| is I + (2 / |q|^2) Q(q), Q the quadratic terms of toRotationMatrix. Returns
/// |q|^2 (in exact arithmetic >= 1 for a finite R: the branch's t^2 term is 1 plus a
/// non-negative number; integrate tests it).
inline double orthonormalise(Mat3& R) {
  double q[4];  // x, y, z, w
  const double tr = R.trace();
  if (tr > 0.0) {
    q[3] = tr + 1.0;
    q[0] = R(2, 1) - R(1, 2);
    q[1] = R(0, 2) - R(2, 0);
    q[2] = R(1, 0) - R(0, 1);
  } else {
    int i = 0;
    if (R(1, 1) > R(0, 0)) i = 1;
    if (R(2, 2) > R(i, i)) i = 2;
    const int j = (i + 1) % 3, k = (j + 1) % 3;
    q[i] = R(i, i) - R(j, j) - R(k, k) + 1.0;
    q[3] = R(k, j) - R(j, k);
    q[j] = R(j, i) + R(i, j);
    q[k] = R(k, i) + R(i, k);
  }
  const double n = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const double s = 2.0 / n;
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double sx = s * x, sy = s * y, sz = s * z;
  const double wx = sx * w, wy = sy * w, wz = sz * w, xx = sx * x, xy = sy * x, xz = sz * x;
  const double yy = sy * y, yz = sz * y, zz = sz * z;
  R(0, 0) = 1.0 - (yy + zz);
  R(0, 1) = xy - wz;
  R(0, 2) = xz + wy;
  R(1, 0) = xy + wz;
  R(1, 1) = 1.0 - (xx + zz);
  R(1, 2) = yz - wx;
  R(2, 0) = xz - wy;
  R(2, 1) = yz + wx;
  R(2, 2) = 1.0 - (xx + yy);
  return n;
}

/// One Lie-group Euler step of (eq:EsRRBM): exp(-h hat(V_wi)) g_bar exp(h hat(u)), the rotation
/// then re-orthonormalised through a unit quaternion (round-off drift over long runs). `unit`
/// (optional) tells whether the result is finite and its rotation that of a quaternion of
/// |q|^2 >= 1, so orthonormal to round-off (|R^T R - I| below 1e-14 entrywise, det R = 1 to
/// round-off): check_pose accepts it, and also its product with a rotation that it accepts with
/// room (see InProcessVmo::step).
inline Pose integrate(const Pose& g_bar, const Vec6& V_wi, const Vec6& u, double h,
                      bool* unit = nullptr) {
  Pose e;
  exp_se3(h * u, e.R, e.p);
  Pose g = compose(g_bar, e);
  if (!V_wi.isZero(0.0)) {
    Pose m;
    exp_se3(-h * V_wi, m.R, m.p);
    g = compose(m, g);
  }
  const double n = orthonormalise(g.R);
  if (unit) *unit = n >= 1.0 && finite(g);
  return g;
}

/// max |R^T R - I| entrywise (the Gram matrix is symmetric: six entries).
inline double gram_error(const Mat3& R) {
  double worst = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      const double gram = R(0, a) * R(0, b) + R(1, a) * R(1, b) + R(2, a) * R(2, b);
      worst = std::max(worst, std::abs(gram - (a == b ? 1.0 : 0.0)));
    }
  return worst;
}

/// The pose part of CameraObserver::receive's check: finite, |R^T R - I| <= 1e-6 entrywise and
/// det R > 0.
inline MessageVerdict check_pose(const Pose& g) {
  if (!finite(g)) return MessageVerdict::not_finite;
  if (!(gram_error(g.R) <= 1e-6) || !(g.R.determinant() > 0.0))
    return MessageVerdict::not_a_rotation;
  return MessageVerdict::accepted;
}

/// Whether check_pose accepts g_w R for every rotation R that integrate reports as `unit`, when
/// g_w R is finite: |R_w^T R_w - I| <= 1e-7 entrywise and det R_w > 0. Then (R_w R)^T R_w R =
/// R^T (R_w^T R_w) R is within 3e-7 (the 2-norm of R_w^T R_w - I is at most 3e-7, R is
/// orthogonal to round-off) plus round-off (1e-14) of I, below check_pose's 1e-6, and
/// det(R_w R) = det R_w det R > 0.
inline bool check_has_room(const Pose& g_w) {
  return g_w.R.allFinite() && gram_error(g_w.R) <= 1e-7 && g_w.R.determinant() > 0.0;
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
