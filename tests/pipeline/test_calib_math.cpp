// The calibration's first-order propagation into g* (g_star_uncertainty.hpp) against finite
// differences of g* itself (obs::average_pose, eq:g_ave).
#include <gtest/gtest.h>

#include <random>

#include "netvmo/observer/metrics.hpp"
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
