// The vmo's per-camera arithmetic on compact poses (a 3x3 rotation and a translation, no 4x4
// matrices), shared by CameraObserver's step (through the vmo estimator) and the in-process fast
// path of NetworkedObserver (in_process_vmo.hpp), so that both compute the same bits. Written once
// for a number type: double (Pose, one camera) or X2 (Pose2, two cameras in the lanes of one
// register, lanes.hpp), whose lanes give the bits of the double expressions. The single mutual
// term and the products are the SE3 (Eigen::Isometry3d) expressions to the last bit; the summed
// mutual term, the exponential (lanes.hpp) and the quaternion re-orthonormalisation are cheaper
// forms of the same mathematics, equal to the plain expressions up to round-off (tests
// CameraObserver.StepArithmeticIsThePlainExpressionsToRoundOff).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

#include "lanes.hpp"
#include "netvmo/observer/estimate_message.hpp"
#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/observer_settings.hpp"

namespace netvmo::obs::kernel {

/// A rigid transform g = [R p; 0 1] stored as 12 doubles.
struct Pose {
  using Scalar = double;
  using Vec6 = obs::Vec6;
  Mat3 R;
  Vec3 p;
};

/// Two cameras' transforms, one per lane (lanes.hpp).
struct Pose2 {
  using Scalar = X2;
  using Vec6 = Vec6x2;
  Mat3x2 R;
  Vec3x2 p;
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

inline Pose2 pack(const Pose& a, const Pose& b) {
  Pose2 g;
  for (int i = 0; i < 9; ++i) g.R.m[i] = X2{a.R.data()[i], b.R.data()[i]};
  for (int i = 0; i < 3; ++i) g.p(i) = X2{a.p(i), b.p(i)};
  return g;
}

inline void unpack(const Pose2& g, Pose& a, Pose& b) {
  for (int i = 0; i < 9; ++i) {
    a.R.data()[i] = g.R.m[i][0];
    b.R.data()[i] = g.R.m[i][1];
  }
  for (int i = 0; i < 3; ++i) {
    a.p(i) = g.p(i)[0];
    b.p(i) = g.p(i)[1];
  }
}

inline void unpack(const Vec6x2& v, Vec6& a, Vec6& b) {
  for (int i = 0; i < 6; ++i) {
    a(i) = v(i)[0];
    b(i) = v(i)[1];
  }
}

// Row r of a 3x3 product (Mat3 * Mat3, Mat3 * Vec3, also on the blocks of an Isometry's 4x4
// matrix), summed in the order in which Eigen sums it: ((x0 + x1) + x2) in rows 0 and 1,
// (x0 + (x1 + x2)) in row 2, so that the kernel's results are those of the Eigen expressions to
// the last bit (tests check it).
template <class T>
T product_entry(int r, const T& a0, const T& a1, const T& a2, const T& b0, const T& b1,
                const T& b2) {
  return r < 2 ? (a0 * b0 + a1 * b1) + a2 * b2 : a0 * b0 + (a1 * b1 + a2 * b2);
}

/// a b, as the Isometry product: [R_a R_b, R_a p_b + p_a].
template <class P>
[[gnu::always_inline]] inline P compose(const P& a, const P& b) {
  P g;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      g.R(r, c) =
          product_entry(r, a.R(r, 0), a.R(r, 1), a.R(r, 2), b.R(0, c), b.R(1, c), b.R(2, c));
  for (int r = 0; r < 3; ++r)
    g.p(r) = product_entry(r, a.R(r, 0), a.R(r, 1), a.R(r, 2), b.p(0), b.p(1), b.p(2)) + a.p(r);
  return g;
}

// R_i^T M for 3x3 rotations and vectors, each entry summed in Eigen's order (product_entry).
// A(k, r) = R_i^T(r, k).
template <class P>
struct TransposedProduct {
  using T = typename P::Scalar;
  const decltype(P::R)& A;
  T top(int r, const T& m0, const T& m1, const T& m2) const {  // rows 0 and 1
    return (A(0, r) * m0 + A(1, r) * m1) + A(2, r) * m2;
  }
  T bottom(const T& m0, const T& m1, const T& m2) const {  // row 2
    return A(0, 2) * m0 + (A(1, 2) * m1 + A(2, 2) * m2);
  }
  template <class V3>
  T row(int r, const V3& m) const {
    return r < 2 ? top(r, m(0), m(1), m(2)) : bottom(m(0), m(1), m(2));
  }
  /// e_R(R_i^T B) = vee(sk(R_i^T B)) (eq:ER) into e(3..5): only the six off-diagonal entries of
  /// the product.
  template <class M3>
  void rotation_error(const M3& B, typename P::Vec6& e) const {
    const T s01 = top(0, B(0, 1), B(1, 1), B(2, 1));
    const T s02 = top(0, B(0, 2), B(1, 2), B(2, 2));
    const T s10 = top(1, B(0, 0), B(1, 0), B(2, 0));
    const T s12 = top(1, B(0, 2), B(1, 2), B(2, 2));
    const T s20 = bottom(B(0, 0), B(1, 0), B(2, 0));
    const T s21 = bottom(B(0, 1), B(1, 1), B(2, 1));
    // vee(S) = [S(2,1) - S(1,2), S(0,2) - S(2,0), S(1,0) - S(0,1)] / 2 (lie.hpp)
    e(3) = (s21 - s12) * 0.5;
    e(4) = (s02 - s20) * 0.5;
    e(5) = (s10 - s01) * 0.5;
  }
};

/// E_R(g_i^-1 g_j) for two world-frame estimates (eq:input_f-), without forming the product:
/// [R_i^T (p_j - p_i); e_R(R_i^T R_j)], e_R = sk(.)^vee (eq:ER); the bits of that Eigen
/// expression (Mat3 R_i^T times R_j and times p_j - p_i).
inline Vec6 mutual_error(const Pose& i, const Pose& j) {
  const TransposedProduct<Pose> Rt{i.R};
  const Vec3 d(j.p(0) - i.p(0), j.p(1) - i.p(1), j.p(2) - i.p(2));
  Vec6 e;
  for (int r = 0; r < 3; ++r) e(r) = Rt.row(r, d);
  Rt.rotation_error(j.R, e);
  return e;
}

/// The visual error of the pose error models, E_R(g_bar^-1 g) (eq:ER) for a measured relative
/// pose g (exact: g_io_i, pnp: g_io,PnP), without forming the product: the bits of the Isometry
/// expression E_R(g_bar.inverse(Eigen::Isometry) * g), whose translation is R^T p_g + (-R^T p).
template <class P>
[[gnu::always_inline]] inline typename P::Vec6 pose_error(const P& g_bar, const P& g) {
  const TransposedProduct<P> Rt{g_bar.R};
  typename P::Vec6 e;
  for (int r = 0; r < 3; ++r) e(r) = Rt.row(r, g.p) - Rt.row(r, g_bar.p);
  Rt.rotation_error(g.R, e);
  return e;
}

/// The initialised neighbours' world-frame estimates of a round, summed entry by entry in
/// neighbour order, for mutual_sum.
struct PoseSum {
  Pose sum{Mat3::Zero(), Vec3::Zero()};
  int count = 0;
  void add(const Pose& g) {
    sum.R += g.R;
    sum.p += g.p;
    ++count;
  }
};

/// The mutual term sum_{j in N_i} E_R(g_i^-1 g_j) of (eq:input_f-) from the sum of m >= 1
/// neighbours' estimates: E_R (eq:ER) is linear in g_j's entries, [R_i^T (p_j - p_i);
/// vee(sk(R_i^T R_j))], so the sum is [R_i^T (sum_j p_j - m p_i); vee(sk(R_i^T sum_j R_j))]: one
/// 3x3 product instead of one per neighbour. Equal to the sum of mutual_error terms up to
/// round-off (a few units in the last place of the summands; a test bounds it).
template <class P>
[[gnu::always_inline]] inline typename P::Vec6 mutual_sum(const P& i, const P& sum,
                                                          const typename P::Scalar& m) {
  using T = typename P::Scalar;
  const auto& A = i.R;  // R_i^T(r, k) = A(k, r)
  const auto& B = sum.R;
  const T d0 = sum.p(0) - m * i.p(0), d1 = sum.p(1) - m * i.p(1), d2 = sum.p(2) - m * i.p(2);
  const auto dot = [&A](int r, const T& x0, const T& x1, const T& x2) {  // row r of R_i^T x
    return A(0, r) * x0 + A(1, r) * x1 + A(2, r) * x2;
  };
  typename P::Vec6 e;
  e(0) = dot(0, d0, d1, d2);
  e(1) = dot(1, d0, d1, d2);
  e(2) = dot(2, d0, d1, d2);
  // vee(S) = [S(2,1) - S(1,2), S(0,2) - S(2,0), S(1,0) - S(0,1)] / 2 (lie.hpp), S = R_i^T B
  e(3) = (dot(2, B(0, 1), B(1, 1), B(2, 1)) - dot(1, B(0, 2), B(1, 2), B(2, 2))) * 0.5;
  e(4) = (dot(0, B(0, 2), B(1, 2), B(2, 2)) - dot(2, B(0, 0), B(1, 0), B(2, 0))) * 0.5;
  e(5) = (dot(1, B(0, 0), B(1, 0), B(2, 0)) - dot(0, B(0, 1), B(1, 1), B(2, 1))) * 0.5;
  return e;
}

/// The mutual term over the initialised neighbours nb (zero when there is none).
inline Vec6 mutual_sum(const Pose& i, const PoseSum& nb) {
  if (nb.count == 0) return Vec6::Zero();
  return mutual_sum(i, nb.sum, static_cast<double>(nb.count));
}

inline bool finite(const Pose& g) {
  return g.R.allFinite() && g.p.allFinite();
}

/// R re-orthonormalised through the unnormalised quaternion q = (x, y, z, w): the rotation of
/// q / |q| is I + (2 / |q|^2) Q(q), Q the quadratic terms of Eigen's toRotationMatrix. Returns
/// |q|^2.
template <class M3, class T>
[[gnu::always_inline]] inline T rotation_of_quaternion(M3& R, const T& x, const T& y, const T& z,
                                                       const T& w) {
  const T n = x * x + y * y + z * z + w * w;
  const T s = 2.0 / n;
  const T sx = s * x, sy = s * y, sz = s * z;
  const T wx = sx * w, wy = sy * w, wz = sz * w, xx = sx * x, xy = sy * x, xz = sz * x;
  const T yy = sy * y, yz = sz * y, zz = sz * z;
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

/// The branch of Shoemake's conversion of R to a quaternion (Eigen's Quaternion(R)): -1 where
/// the trace (summed as Eigen sums it) is positive, otherwise the index of the largest diagonal
/// entry.
inline int quaternion_branch(double r00, double r11, double r22) {
  if (r00 + (r11 + r22) > 0.0) return -1;
  int i = 0;
  if (r11 > r00) i = 1;
  if (r22 > (i == 0 ? r00 : r11)) i = 2;
  return i;
}

/// Shoemake's conversion of R to a quaternion q = (x, y, z, w), times 2t (t = sqrt(t^2), the
/// branch's t^2 term), on the given branch (quaternion_branch; Eigen's Quaternion(R), branch for
/// branch).
template <class M3, class T>
[[gnu::always_inline]] inline void quaternion_on(const M3& R, int branch, T (&q)[4]) {
  if (branch < 0) {
    q[3] = R(0, 0) + (R(1, 1) + R(2, 2)) + 1.0;
    q[0] = R(2, 1) - R(1, 2);
    q[1] = R(0, 2) - R(2, 0);
    q[2] = R(1, 0) - R(0, 1);
    return;
  }
  const int i = branch, j = (i + 1) % 3, k = (j + 1) % 3;
  q[i] = R(i, i) - R(j, j) - R(k, k) + 1.0;
  q[3] = R(k, j) - R(j, k);
  q[j] = R(j, i) + R(i, j);
  q[k] = R(k, i) + R(i, k);
}

/// R re-orthonormalised through its unit quaternion: Eigen's Quaternion(R).normalized()
/// .toRotationMatrix() (Shoemake's conversion, quaternion_on) with the quaternion left
/// unnormalised: the conversion's q times 2t needs no square root (rotation_of_quaternion).
/// Returns |q|^2 (in exact arithmetic >= 1 for a finite R: the branch's t^2 term is 1 plus a
/// non-negative number; integrate tests it).
inline double orthonormalise(Mat3& R) {
  double q[4];
  quaternion_on(R, quaternion_branch(R(0, 0), R(1, 1), R(2, 2)), q);
  return rotation_of_quaternion(R, q[0], q[1], q[2], q[3]);
}

/// Two rotations at once, each lane on its own branch of the conversion.
inline X2 orthonormalise(Mat3x2& R) {
  const int b0 = quaternion_branch(R(0, 0)[0], R(1, 1)[0], R(2, 2)[0]);
  const int b1 = quaternion_branch(R(0, 0)[1], R(1, 1)[1], R(2, 2)[1]);
  X2 q[4];
  quaternion_on(R, b0, q);
  if (b1 != b0) {  // lane 1 from its own branch
    X2 q1[4];
    quaternion_on(R, b1, q1);
    const Mask2 first = mask2(true, false);
    for (int e = 0; e < 4; ++e) q[e] = select(first, q[e], q1[e]);
  }
  return rotation_of_quaternion(R, q[0], q[1], q[2], q[3]);
}

/// g_bar exp(h hat(u)), the right-hand factor of one Lie-group Euler step of (eq:EsRRBM), not yet
/// re-orthonormalised.
template <class P>
[[gnu::always_inline]] inline P right_step(const P& g_bar, const typename P::Vec6& u, double h) {
  typename P::Vec6 hu;
  for (int r = 0; r < 6; ++r) hu(r) = h * u(r);
  P e;
  exp_se3(hu, e.R, e.p);
  return compose(g_bar, e);
}

/// One Lie-group Euler step of (eq:EsRRBM): exp(-h hat(V_wi)) g_bar exp(h hat(u)), the rotation
/// then re-orthonormalised through a unit quaternion (round-off drift over long runs). `unit`
/// (optional) tells whether the result is finite and its rotation that of a quaternion of
/// |q|^2 >= 1, so orthonormal to round-off (|R^T R - I| below 1e-14 entrywise, det R = 1 to
/// round-off): check_pose accepts it, and also its product with a rotation that it accepts with
/// room (see InProcessVmo::step).
inline Pose integrate(const Pose& g_bar, const Vec6& V_wi, const Vec6& u, double h,
                      bool* unit = nullptr) {
  Pose g = right_step(g_bar, u, h);
  if (!V_wi.isZero(0.0)) {
    const Vec6 left = -h * V_wi;
    Pose m;
    exp_se3(left, m.R, m.p);
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

/// u_ei of (eq:input_f-) from the summed mutual term and the visual error, where the camera
/// sees the target (`sees`: a bool, or a Mask2 for two cameras): k_s mutual + k_e visual.
template <class V6, class M>
[[gnu::always_inline]] inline V6 vmo_input(const ObserverSettings& s, const V6& mutual,
                                           const V6& visual, const M& sees) {
  V6 u;
  for (int r = 0; r < 6; ++r) {
    const auto base = s.k_s * mutual(r);
    u(r) = select(sees, base + s.k_e * visual(r), base);
  }
  return u;
}

/// u_ei of (eq:input_f-) from the summed mutual term and the visual error (null: not visible).
inline Vec6 vmo_input(const ObserverSettings& s, const Vec6& mutual, const Vec6* visual) {
  return vmo_input(s, mutual, visual ? *visual : mutual, visual != nullptr);
}

}  // namespace netvmo::obs::kernel
