// The paper's metrics: g* (eq:g_ave) with the Section 5 numbers, optimality of g*, energies and
// epsilon-levels against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "netvmo/observer/metrics.hpp"

using namespace netvmo::obs;

namespace {
std::vector<SE3> paper_targets() {
  return {make_pose({0.55, 1.00, -1.91}, {0.30, 0.19, 0.21}),
          make_pose({0.30, 0.80, -1.84}, {0.21, 0.30, 0.19}),
          make_pose({0.56, 1.05, -2.00}, {0.29, 0.20, 0.31})};
}
double objective(const SE3& g, const std::vector<SE3>& targets) {
  double s = 0.0;
  for (const auto& t : targets) s += psi(g.inverse() * t);  // (eq:g_ave)
  return s;
}
}  // namespace

TEST(Metrics, PaperAverageToThePrintedDecimals) {
  const SE3 g = average_pose(paper_targets());
  const Vec3 p = g.translation();
  const Vec3 r = rotvec(g);
  const Vec3 p_paper(0.47, 0.95, -1.92), r_paper(0.27, 0.23, 0.24);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(p[k], p_paper[k], 0.005) << k;
    EXPECT_NEAR(r[k], r_paper[k], 0.005) << k;
  }
}

TEST(Metrics, AverageMinimisesTheObjective) {
  const auto t = paper_targets();
  const SE3 g = average_pose(t);
  const double f0 = objective(g, t);
  for (int k = 0; k < 6; ++k) {
    for (double s : {1e-3, -1e-3}) {
      Vec6 d = Vec6::Zero();
      d[k] = s;
      EXPECT_GT(objective(g * exp_se3(d), t), f0) << k;
    }
  }
}

TEST(Metrics, EnergiesAndLevelsMatchClosedForms) {
  const SE3 g_star = make_pose({1, 2, 3}, {0.1, 0.0, 0.0});
  const double th = 0.3;
  std::vector<SE3> est = {g_star, g_star * make_pose({0.2, 0, 0}, {0, 0, th})};
  const Energies e = energies(est, g_star);
  EXPECT_NEAR(e.U_p, 0.5 * 0.04, 1e-14);
  EXPECT_NEAR(e.U_R, 2.0 * (1.0 - std::cos(th)), 1e-14);
  const std::vector<SE3> targets = {g_star * make_pose({0.1, 0, 0}, {0.2, 0, 0}),
                                    g_star * make_pose({-0.1, 0, 0}, {-0.2, 0, 0})};
  const Spread s = spread(targets, g_star);
  EXPECT_NEAR(s.rho_p, 0.02, 1e-14);
  EXPECT_NEAR(s.rho_R, 2 * 2.0 * (1.0 - std::cos(0.2)), 1e-14);
  EXPECT_NEAR(s.phi_m, 2.0 * (1.0 - std::cos(0.2)), 1e-14);
  const EpsLevels l = eps_levels(est, g_star, s, 2);
  EXPECT_NEAR(l.eps_p, (0.04 / 2) / (0.02 / 2), 1e-12);
  EXPECT_NEAR(l.eps_R, (e.U_R / 2) / (s.rho_R / 2), 1e-12);
}

TEST(Metrics, Theorem1BoundTendsToTheOffsetAndGrowsWithK) {
  Spread s;
  s.phi_m = 0.02;  // beta = 1 - sqrt(0.04) = 0.8
  const double W = 3, diam = 2;
  EXPECT_NEAR(theorem1_bound(1e-14, s, W, diam, 3).eps_R, theorem1_orientation_offset(s), 1e-6);
  EXPECT_NEAR(theorem1_bound(1e-14, s, W, diam, 3).eps_p, 0.0, 1e-6);
  // A closed form at k = 0.01: eps_p = (sqrt(0.03) + sqrt(1 - (1 - sqrt(0.03))^2))^2.
  const double a = std::sqrt(0.01 * diam * 3 / 2), b = 1 - std::sqrt(0.03);
  EXPECT_NEAR(theorem1_bound(0.01, s, W, diam, 3).eps_p, std::pow(a + std::sqrt(1 - b * b), 2),
              1e-12);
  EXPECT_LT(theorem1_bound(0.01, s, W, diam, 3).eps_R, theorem1_bound(0.02, s, W, diam, 3).eps_R);
  EXPECT_TRUE(std::isinf(theorem1_bound(0.8 / 3, s, W, diam, 3).eps_R));  // k W = beta
}

namespace netvmo::obs {
namespace {
// Two neighbours 0.1 m either side along x and one turned 0.2 rad about z: the closed form.
TEST(NeighbourSpread, IsTheSecondMomentOfTheNeighboursAboutTheOwnEstimate) {
  const SE3 own = make_pose(Vec3(1, 2, 3), Vec3(0.3, -0.2, 0.1));
  EXPECT_FALSE(neighbour_spread(own, {}).has_value());
  SE3 a = own, b = own;
  a.translation() += Vec3(0.1, 0, 0);
  b.translation() -= Vec3(0.1, 0, 0);
  b.linear() = exp_so3(Vec3(0, 0, 0.2)) * own.linear();  // 0.2 rad about the world's z
  const auto C = neighbour_spread(own, {a, b});
  ASSERT_TRUE(C.has_value());
  Eigen::Matrix<double, 6, 6> expected = Eigen::Matrix<double, 6, 6>::Zero();
  expected(0, 0) = (0.01 + 0.01) / 2;
  expected(5, 5) = 0.04 / 2;
  expected(0, 5) = expected(5, 0) = (-0.1 * 0.2) / 2;
  EXPECT_LT((*C - expected).norm(), 1e-12);
  // Neighbours that agree with the camera: zero.
  EXPECT_LT(neighbour_spread(own, {own, own})->norm(), 1e-12);
}
}  // namespace
}  // namespace netvmo::obs
