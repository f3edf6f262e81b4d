// Two cameras in one register: a 2-lane vector of doubles (GCC's and Clang's vector extensions;
// SSE2 on x86-64, NEON on AArch64), for the vmo kernel (pose_kernel.hpp), which is written once for
// a number type T: double (one camera) or X2 (two cameras, one per lane). Each lane's +, -, * and /
// is the IEEE operation on one double, so an expression on X2 gives in each lane the bits of the
// same expression on doubles (tests PoseKernel.*). Functions of one double (sqrt, sin, cos) and
// branches run lane by lane. The kernel's templates are always inlined into the step
// (InProcessVmo::step_pair): called out of line, they pass their X2 values through memory (one
// thread, 10,000 cameras: 16.5 -> 15.5 ms a frame, tools/bench/bench_observer).
//
// Also here, because lie.cpp's exp_se3 is the kernel's: the exponential of se(3) written once for
// both number types.
#pragma once

#include <cmath>
#include <cstdint>

#include "netvmo/observer/lie.hpp"

namespace netvmo::obs::kernel {

/// Two doubles, one per camera.
using X2 = double __attribute__((vector_size(16)));
/// A mask of two lanes: all bits set where true.
using Mask2 = std::int64_t __attribute__((vector_size(16)));

inline Mask2 mask2(bool a, bool b) {
  return Mask2{a ? -1 : 0, b ? -1 : 0};
}

/// m ? a : b, lane by lane for X2.
inline double select(bool m, double a, double b) {
  return m ? a : b;
}
inline X2 select(Mask2 m, X2 a, X2 b) {
  return reinterpret_cast<X2>((m & reinterpret_cast<Mask2>(a)) | (~m & reinterpret_cast<Mask2>(b)));
}

/// A 3x3 matrix of X2, column-major like Eigen's, with Eigen's accessors.
struct Mat3x2 {
  X2 m[9];
  X2& operator()(int r, int c) { return m[3 * c + r]; }
  const X2& operator()(int r, int c) const { return m[3 * c + r]; }
};

/// An N-vector of X2 with Eigen's accessor.
template <int N>
struct VecX2 {
  X2 v[N];
  X2& operator()(int i) { return v[i]; }
  const X2& operator()(int i) const { return v[i]; }
};
using Vec3x2 = VecX2<3>;
using Vec6x2 = VecX2<6>;

/// Below this angle the closed forms of exp and log (here and lie.cpp) lose digits to
/// cancellation; Taylor series instead.
constexpr double kSmallAngle = 1e-4;

/// The coefficients of exp_se3 below from t2 = |w|^2: R = I + a W + a2 W^2 (exp_so3) and the
/// left Jacobian J = I + a2 W + c W^2, W = hat(w): a = sin t / t, a2 = (1 - cos t) / t^2,
/// c = (t - sin t) / t^3, t = |w| (Taylor series in t2, Horner form, below kSmallAngle).
inline void exp_coefficients(double t2, double& a, double& a2, double& c) {
  if (t2 < kSmallAngle * kSmallAngle) {
    a = 1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0));
    a2 = 0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0));
    c = 1.0 / 6.0 - t2 * (1.0 / 120.0);
  } else {
    const double t = std::sqrt(t2), s = std::sin(t), co = std::cos(t);
    const double inv_t = 1.0 / t, inv_t2 = inv_t * inv_t;
    a = s * inv_t;
    a2 = (1.0 - co) * inv_t2;
    c = (t - s) * (inv_t2 * inv_t);
  }
}
inline void exp_coefficients(X2 t2, X2& a, X2& a2, X2& c) {
  for (int l = 0; l < 2; ++l) {
    double al, a2l, cl;
    exp_coefficients(t2[l], al, a2l, cl);
    a[l] = al;
    a2[l] = a2l;
    c[l] = cl;
  }
}

/// exp(hat(V)) of a twist V = [v; w] as a rotation R and a translation p = J v: R = I + a W +
/// a2 W^2 and J = I + a2 W + c W^2 (exp_coefficients), written out with W^2 = w w^T - |w|^2 I,
/// W v = w x v, W^2 v = w x (w x v). V6, M3 and V3 are Eigen's Vec6, Mat3 and Vec3 or the X2
/// ones; the sums in the order of Eigen's squaredNorm and cross, so both give lie.hpp's bits.
template <class V6, class M3, class V3>
[[gnu::always_inline]] inline void exp_se3(const V6& V, M3& R, V3& p) {
  const auto x = V(3), y = V(4), z = V(5);
  const auto t2 = (x * x + y * y) + z * z;
  decltype(t2 + 0.0) a, a2, c;
  exp_coefficients(t2, a, a2, c);
  const auto xx = x * x, yy = y * y, zz = z * z, xy = x * y, xz = x * z, yz = y * z;
  R(0, 0) = 1.0 - a2 * (yy + zz);
  R(1, 1) = 1.0 - a2 * (xx + zz);
  R(2, 2) = 1.0 - a2 * (xx + yy);
  R(0, 1) = a2 * xy - a * z;
  R(1, 0) = a2 * xy + a * z;
  R(0, 2) = a2 * xz + a * y;
  R(2, 0) = a2 * xz - a * y;
  R(1, 2) = a2 * yz - a * x;
  R(2, 1) = a2 * yz + a * x;
  const auto v0 = V(0), v1 = V(1), v2 = V(2);
  const auto wv0 = y * v2 - z * v1, wv1 = z * v0 - x * v2, wv2 = x * v1 - y * v0;  // w x v
  const auto ww0 = y * wv2 - z * wv1, ww1 = z * wv0 - x * wv2, ww2 = x * wv1 - y * wv0;
  p(0) = (v0 + a2 * wv0) + c * ww0;
  p(1) = (v1 + a2 * wv1) + c * ww1;
  p(2) = (v2 + a2 * wv2) + c * ww2;
}

}  // namespace netvmo::obs::kernel
