// The vmo kernel on two cameras at once (kernel::Pose2, lanes.hpp) must give each camera the bits
// that the kernel on one camera (kernel::Pose) gives it: every function of the step, on pairs of
// inputs that take different branches in their two lanes (the quaternion conversion's four, the
// exponential's series and closed form, seeing and not seeing).
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "../../observer/src/pose_kernel.hpp"

using namespace netvmo::obs;
using kernel::Pose;
using kernel::Pose2;
using kernel::X2;

namespace {

bool same_bits(const Pose& a, const Pose& b) {
  return std::memcmp(a.R.data(), b.R.data(), sizeof(double) * 9) == 0 &&
         std::memcmp(a.p.data(), b.p.data(), sizeof(double) * 3) == 0;
}

bool same_bits(const Vec6& a, const Vec6& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * 6) == 0;
}

// Poses whose rotations cover the four branches of the quaternion conversion: small angles
// (trace > 0) and angles near pi about each axis (the largest diagonal entry 0, 1 or 2), some
// scaled off the rotations (the re-orthonormalisation's input is a product of rotations, off by
// round-off; here by more), and translations with exact zeros of either sign.
class Poses {
 public:
  explicit Poses(unsigned seed) : rng_(seed) {}
  Pose next() {
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Vec3 w(U(rng_), U(rng_), U(rng_));
    const int kind = static_cast<int>(rng_() % 5);
    if (kind < 3) {  // near pi about axis `kind`
      w *= 0.2;
      w(kind) = 3.0 + 0.1 * U(rng_);
    } else if (kind == 3) {
      w *= 1e-3;
    }
    Pose g{exp_so3(w), Vec3(U(rng_), U(rng_), U(rng_))};
    if (rng_() % 4 == 0) g.R *= 1.0 + 1e-3 * U(rng_);
    if (rng_() % 7 == 0) g.p(rng_() % 3) = rng_() % 2 ? 0.0 : -0.0;
    return g;
  }
  Vec6 twist(double scale) {
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Vec6 V;
    for (int r = 0; r < 6; ++r) V(r) = U(rng_) * scale;
    if (rng_() % 9 == 0) V(static_cast<int>(rng_() % 6)) = -0.0;
    return V;
  }
  unsigned draw() { return static_cast<unsigned>(rng_()); }

 private:
  std::mt19937 rng_;
};

kernel::Vec6x2 pack(const Vec6& a, const Vec6& b) {
  kernel::Vec6x2 v;
  for (int r = 0; r < 6; ++r) v(r) = X2{a(r), b(r)};
  return v;
}

}  // namespace

TEST(PoseKernel, TwoCamerasAtOnceGiveEachCameraItsOwnBits) {
  Poses poses(77);  // fixed seed
  ObserverSettings s;
  s.k_s = 3.7;  // not 1: the products must not be exact
  s.k_e = 1.3;
  int differs = 0, branch_pairs = 0, mixed_branches = 0, series_lanes = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Pose a = poses.next(), b = poses.next(), c = poses.next(), d = poses.next();
    const Pose2 ab = kernel::pack(a, b), cd = kernel::pack(c, d);
    Pose x, y;
    // compose
    kernel::unpack(kernel::compose(ab, cd), x, y);
    differs += !same_bits(x, kernel::compose(a, c)) + !same_bits(y, kernel::compose(b, d));
    // pose_error
    Vec6 e0, e1;
    kernel::unpack(kernel::pose_error(ab, cd), e0, e1);
    differs += !same_bits(e0, kernel::pose_error(a, c)) + !same_bits(e1, kernel::pose_error(b, d));
    // mutual_sum, 1 to 4 neighbours a lane
    kernel::PoseSum na, nb;
    const int ma = 1 + static_cast<int>(poses.draw() % 4),
              mb = 1 + static_cast<int>(poses.draw() % 4);
    for (int j = 0; j < 4; ++j) {
      const Pose g = poses.next();
      if (j < ma) na.add(g);
      if (j < mb) nb.add(kernel::compose(g, a));
    }
    kernel::unpack(
        kernel::mutual_sum(ab, kernel::pack(na.sum, nb.sum),
                           X2{static_cast<double>(na.count), static_cast<double>(nb.count)}),
        e0, e1);
    differs +=
        !same_bits(e0, kernel::mutual_sum(a, na)) + !same_bits(e1, kernel::mutual_sum(b, nb));
    // vmo_input, each lane seeing or not
    const Vec6 m0 = poses.twist(1.0), m1 = poses.twist(1.0), v0 = poses.twist(1.0),
               v1 = poses.twist(1.0);
    const bool sees0 = poses.draw() % 2, sees1 = poses.draw() % 2;
    kernel::unpack(kernel::vmo_input(s, pack(m0, m1), pack(v0, v1), kernel::mask2(sees0, sees1)),
                   e0, e1);
    differs += !same_bits(e0, kernel::vmo_input(s, m0, sees0 ? &v0 : nullptr)) +
               !same_bits(e1, kernel::vmo_input(s, m1, sees1 ? &v1 : nullptr));
    // right_step (the exponential: one lane's rotation below the series' angle in some pairs)
    const double h = 1.0 / 420.0;
    const Vec6 u0 = poses.twist(trial % 3 == 0 ? 1e-3 : 10.0), u1 = poses.twist(10.0);
    series_lanes += (h * u0.tail<3>()).norm() < kernel::kSmallAngle;
    Pose2 g = kernel::right_step(ab, pack(u0, u1), h);
    kernel::unpack(g, x, y);
    differs +=
        !same_bits(x, kernel::right_step(a, u0, h)) + !same_bits(y, kernel::right_step(b, u1, h));
    // orthonormalise, the lanes on the same or different branches
    const int b0 = kernel::quaternion_branch(x.R(0, 0), x.R(1, 1), x.R(2, 2));
    const int b1 = kernel::quaternion_branch(y.R(0, 0), y.R(1, 1), y.R(2, 2));
    ++branch_pairs;
    mixed_branches += b0 != b1;
    const X2 n = kernel::orthonormalise(g.R);
    Pose xo = x, yo = y;
    const double n0 = kernel::orthonormalise(xo.R), n1 = kernel::orthonormalise(yo.R);
    kernel::unpack(g, x, y);
    differs += !same_bits(x, xo) + !same_bits(y, yo);
    const double lane0 = n[0], lane1 = n[1];
    differs += std::memcmp(&lane0, &n0, sizeof(double)) != 0;
    differs += std::memcmp(&lane1, &n1, sizeof(double)) != 0;
  }
  EXPECT_EQ(differs, 0);
  // The cases above happened: lanes on different branches and the exponential's series.
  EXPECT_GT(mixed_branches, branch_pairs / 4);
  EXPECT_LT(mixed_branches, branch_pairs);
  EXPECT_GT(series_lanes, 1000);
}

// A lane that does not see keeps the mutual term's bits, signed zeros included (select, not an
// addition of zero: -0 + 0 is +0).
TEST(PoseKernel, ALaneThatDoesNotSeeKeepsTheMutualTermsSignedZeros) {
  ObserverSettings s;
  Vec6 m = Vec6::Zero();
  m(0) = -0.0;
  m(4) = -0.0;
  const Vec6 v = Vec6::Constant(0.0);
  Vec6 e0, e1;
  kernel::unpack(kernel::vmo_input(s, pack(m, m), pack(v, v), kernel::mask2(false, true)), e0, e1);
  EXPECT_TRUE(std::signbit(e0(0)) && std::signbit(e0(4)));
  EXPECT_TRUE(same_bits(e0, kernel::vmo_input(s, m, nullptr)));
  EXPECT_FALSE(std::signbit(e1(0)));  // seeing: k_s (-0) + k_e (+0) = +0
  EXPECT_TRUE(same_bits(e1, kernel::vmo_input(s, m, &v)));
}
