// The calibration's first-order propagation into g* (g_star_uncertainty.hpp) against finite
// differences of g* itself (obs::average_pose, eq:g_ave), and the correlation of corner errors
// from frame to frame (calib::frame_correlation) against closed forms.
#include <gtest/gtest.h>

#include <random>

#include "netvmo/observer/metrics.hpp"
#include "netvmo/pipeline/calib/calibrate.hpp"
#include "netvmo/pipeline/calib/g_star_uncertainty.hpp"

using namespace netvmo;
using Mat6 = Eigen::Matrix<double, 6, 6>;

namespace {
// The perturbation of calibrate.hpp: (R exp(hat(dtheta)), p + dp).
obs::SE3 perturbed(const obs::SE3& g, const obs::Vec6& e) {
  obs::SE3 out = g;
  out.linear() = g.linear() * obs::exp_so3(e.tail<3>());
  out.translation() = g.translation() + e.head<3>();
  return out;
}
}  // namespace

TEST(CalibMath, GStarCovarianceIsTheFiniteDifferenceJacobianSquared) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const auto rnd = [&] { return obs::Vec3(n(rng), n(rng), n(rng)); };
  const obs::SE3 g_wo = obs::make_pose(rnd(), 0.3 * rnd());
  std::vector<obs::SE3> g_wi, g_io;
  std::vector<calib::GStarTerm> terms;
  for (int i = 0; i < 4; ++i) {
    g_wi.push_back(obs::make_pose(2.0 * rnd(), 1.0 * rnd()));
    // Fictitious targets a little apart (the believed poses are not the true ones).
    g_io.push_back(g_wi.back().inverse() * obs::make_pose(0.05 * rnd(), 0.05 * rnd()) * g_wo);
    Eigen::Matrix<double, 6, 6> L = Eigen::Matrix<double, 6, 6>::Random() * 1e-3;
    terms.push_back({g_wi.back(), (g_wi.back() * g_io.back()).translation(), L * L.transpose()});
  }
  const auto g_star = [&](int cam, const obs::Vec6& e) {
    std::vector<obs::SE3> f;
    for (int i = 0; i < 4; ++i)
      f.push_back((i == cam ? perturbed(g_wi[size_t(i)], e) : g_wi[size_t(i)]) * g_io[size_t(i)]);
    return obs::average_pose(f);
  };
  const obs::SE3 g0 = g_star(-1, obs::Vec6::Zero());
  Mat6 expected = Mat6::Zero();
  const double h = 1e-6;
  for (int i = 0; i < 4; ++i) {
    Mat6 J;  // d[p*; theta*(world axes)] / d e_i, central differences
    for (int k = 0; k < 6; ++k) {
      obs::Vec6 e = obs::Vec6::Zero();
      e[k] = h;
      const obs::SE3 a = g_star(i, e), b = g_star(i, -e);
      J.block<3, 1>(0, k) = (a.translation() - b.translation()) / (2 * h);
      J.block<3, 1>(3, k) = (obs::log_so3(a.linear() * g0.linear().transpose()) -
                             obs::log_so3(b.linear() * g0.linear().transpose())) /
                            (2 * h);
    }
    expected += J * terms[size_t(i)].covariance * J.transpose();
  }
  const Mat6 got = calib::g_star_covariance(terms);
  // The rotations of the fictitious targets differ by ~0.05 rad: the chordal mean's first-order
  // weights are equal to O(0.05^2), so 1 % of the covariance's size.
  EXPECT_LT((got - expected).norm(), 1e-2 * expected.norm()) << got << "\n\n" << expected;
  EXPECT_TRUE(calib::g_star_covariance({}).isZero());
}

namespace {
// Residuals of `groups` (tag, corner) over `frames` frames: b_g + e_gf, b_g ~ N(0, sb^2) fixed
// per group (the error that repeats), e_gf ~ N(0, se^2) new each frame; seeded.
std::vector<calib::CameraResult::Residual> residuals(int groups, int frames, double sb, double se,
                                                     std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<calib::CameraResult::Residual> out;
  for (int g = 0; g < groups; ++g) {
    const double bu = sb * n(rng), bv = sb * n(rng);
    for (int f = 0; f < frames; ++f)
      out.push_back({f, g / 4, g % 4, bu + se * n(rng), bv + se * n(rng), true});
  }
  return out;
}
}  // namespace

// Errors that repeat exactly (no noise): rho = 1 and the covariance is one frame's (inflation =
// frames); errors that never repeat: rho ~ 0, inflation ~ 1; half and half (sb = se): rho ~ 1/2,
// the intraclass correlation sb^2 / (sb^2 + se^2). Sampling spread of the estimate with G groups
// of n: about sqrt(2 / (n (n - 1) G)) (1 - rho)(1 + (n - 1) rho) (Fisher), so the bounds below
// are several of its standard deviations.
TEST(CalibMath, FrameCorrelationMatchesItsClosedForms) {
  const auto same = calib::frame_correlation(residuals(12, 6, 0.5, 0.0, 1));
  EXPECT_DOUBLE_EQ(same.rho, 1.0);
  EXPECT_DOUBLE_EQ(same.frames, 6.0);
  EXPECT_DOUBLE_EQ(same.inflation, 6.0);

  const auto fresh = calib::frame_correlation(residuals(200, 10, 0.0, 0.3, 2));
  EXPECT_LT(fresh.rho, 0.03);  // (spread ~0.01)
  EXPECT_LT(fresh.inflation, 1.3);
  EXPECT_GE(fresh.inflation, 1.0);

  const auto half = calib::frame_correlation(residuals(200, 10, 0.3, 0.3, 3));
  EXPECT_NEAR(half.rho, 0.5, 0.08);  // (spread ~0.025)
  EXPECT_NEAR(half.inflation, 1.0 + 9 * half.rho, 1e-12);

  // Unused residuals do not count; one frame, or one group, is no evidence.
  auto some = residuals(12, 6, 0.5, 0.0, 4);
  for (auto& r : some) r.used = r.frame == 0;
  EXPECT_EQ(calib::frame_correlation(some).inflation, 1.0);
  EXPECT_EQ(calib::frame_correlation(residuals(1, 8, 0.5, 0.1, 5)).inflation, 1.0);
  EXPECT_EQ(calib::frame_correlation({}).rho, 0.0);
}
