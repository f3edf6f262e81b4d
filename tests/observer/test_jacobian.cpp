// The image Jacobian against finite differences of the projection, and the error
// reconstruction (eq:eei) against the exact error E_R(g_bar^-1 g) for small errors.
#include <gtest/gtest.h>

#include "netvmo/observer/jacobian.hpp"

using namespace netvmo::obs;

namespace {
// g_e(d) = (d_p, exp(d_w)): the perturbation whose E_R is d to first order.
SE3 perturbation(const Vec6& d) {
  return make_pose(d.head<3>(), d.tail<3>());
}

const SE3 kGBar = make_pose(Vec3(0.25, -0.15, 1.9), Vec3(2.9, 0.3, -0.2));  // tag facing camera
}  // namespace

TEST(Jacobian, SquareCornersAreInDetectionOrder) {
  const auto m = FeatureModel::square(0.2);
  ASSERT_EQ(m.points_o.size(), 4u);
  EXPECT_TRUE(m.points_o[0].isApprox(Vec3(-0.1, -0.1, 0)));
  EXPECT_TRUE(m.points_o[1].isApprox(Vec3(0.1, -0.1, 0)));
  EXPECT_TRUE(m.points_o[2].isApprox(Vec3(0.1, 0.1, 0)));
  EXPECT_TRUE(m.points_o[3].isApprox(Vec3(-0.1, 0.1, 0)));
}

TEST(Jacobian, ProjectionIsPerspectiveDivision) {
  FeatureModel m;
  m.points_o = {Vec3(0.1, 0.2, 0.0)};
  m.lambda = 0.03;
  const SE3 g = make_pose(Vec3(0, 0, 2), Vec3::Zero());
  const Eigen::VectorXd f = project(g, m);
  EXPECT_NEAR(f[0], 0.03 * 0.1 / 2.0, 1e-15);
  EXPECT_NEAR(f[1], 0.03 * 0.2 / 2.0, 1e-15);
  EXPECT_THROW(project(make_pose(Vec3(0, 0, -2), Vec3::Zero()), m), std::domain_error);
}

TEST(Jacobian, MatchesCentralFiniteDifferences) {
  for (double lambda : {1.0, 0.03}) {
    const auto m = FeatureModel::square(0.2, lambda);
    const Eigen::MatrixXd J = image_jacobian(kGBar, m);
    ASSERT_EQ(J.rows(), 8);
    ASSERT_EQ(J.cols(), 6);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d[k] = h;
      const Eigen::VectorXd fd =
          (project(kGBar * perturbation(d), m) - project(kGBar * perturbation(-d), m)) / (2 * h);
      EXPECT_LT((J.col(k) - fd).norm(), 1e-8 * lambda) << "column " << k;
    }
  }
}

TEST(Jacobian, ReconstructionApproximatesExactErrorToSecondOrder) {
  const auto m = FeatureModel::square(0.2);
  const Vec6 dir = (Vec6() << 0.3, -0.2, 0.5, 0.4, -0.6, 0.2).finished().normalized();
  double prev_err = 0.0;
  for (double s : {1e-2, 5e-3, 2.5e-3}) {
    const SE3 g_true = kGBar * make_pose(s * dir.head<3>(), s * dir.tail<3>());
    const Vec6 exact = E_R(kGBar.inverse() * g_true);
    const Vec6 rec = reconstruct_error(kGBar, project(g_true, m), m);  // (eq:eei)
    const double err = (rec - exact).norm();
    EXPECT_LT(err, 0.05 * exact.norm()) << "scale " << s;
    // Second order: halving the error roughly quarters the mismatch.
    if (prev_err > 0.0) {
      EXPECT_LT(err, 0.35 * prev_err);
    }
    prev_err = err;
  }
}

TEST(Jacobian, ReconstructionIsZeroAtTheTruth) {
  const auto m = FeatureModel::square(0.15);
  EXPECT_LT(reconstruct_error(kGBar, project(kGBar, m), m).norm(), 1e-12);
}

// The reconstruction sums J^T J and J^T (f - f_bar) over the points' row blocks; it equals the
// pseudo-inverse through the whole 2m x 6 Jacobian up to round-off: the same products summed in
// another order (a few eps), amplified by the 6x6 solve's conditioning. Measured: at most 7e-15 of
// the error's size; the bound is 1e-12.
TEST(Jacobian, ReconstructionEqualsTheWholeJacobiansPseudoInverse) {
  const auto m = FeatureModel::square(0.2, 0.03);
  const Vec6 dir = (Vec6() << 0.3, -0.2, 0.5, 0.4, -0.6, 0.2).finished().normalized();
  for (double s : {1e-1, 1e-3, 1e-6}) {
    const Eigen::VectorXd f = project(kGBar * perturbation(s * dir), m);
    const Eigen::MatrixXd J = image_jacobian(kGBar, m);
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Vec6 whole = JtJ.ldlt().solve(J.transpose() * (f - project(kGBar, m)));
    EXPECT_LT((reconstruct_error(kGBar, f, m) - whole).norm(), 1e-12 * whole.norm()) << s;
  }
}

TEST(Jacobian, AFeatureVectorOfAnotherSizeIsRefused) {
  const auto m = FeatureModel::square(0.2);
  const Eigen::VectorXd f = project(kGBar, m);
  try {
    reconstruct_error(kGBar, f.head(6), m);
    FAIL() << "no exception";
  } catch (const std::domain_error& e) {
    EXPECT_STREQ(e.what(), "feature vector of 6 values for a target of 4 feature points");
  }
}
