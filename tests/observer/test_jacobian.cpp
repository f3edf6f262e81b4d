// The image Jacobian against finite differences of the projection, and the error
// reconstruction (eq:eei) against the exact error E_R(g_bar^-1 g) for small errors, also for a
// tag bundle (points of several tags).
#include <gtest/gtest.h>

#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/jacobian.hpp"

using namespace netvmo::obs;

namespace {
// g_e(d) = (d_p, exp(d_w)): the perturbation whose E_R is d to first order.
SE3 perturbation(const Vec6& d) {
  return make_pose(d.head<3>(), d.tail<3>());
}

const SE3 kGBar = make_pose(Vec3(0.25, -0.15, 1.9), Vec3(2.9, 0.3, -0.2));  // tag facing camera

// Central finite differences of project() along E_R perturbations of g (step 1e-6), 2m x 6.
Eigen::MatrixXd finite_difference_jacobian(const SE3& g, const FeatureModel& m) {
  const double h = 1e-6;
  Eigen::MatrixXd fd(2 * static_cast<Eigen::Index>(m.points_o.size()), 6);
  for (int k = 0; k < 6; ++k) {
    Vec6 d = Vec6::Zero();
    d[k] = h;
    fd.col(k) = (project(g * perturbation(d), m) - project(g * perturbation(-d), m)) / (2 * h);
  }
  return fd;
}
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
    const Eigen::MatrixXd fd = finite_difference_jacobian(kGBar, m);
    for (int k = 0; k < 6; ++k)
      EXPECT_LT((J.col(k) - fd.col(k)).norm(), 1e-8 * lambda) << "column " << k;
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

// A tag bundle: two tags on faces 45 degrees apart (datasets/tag_bundle.yaml's wedge). J stacked
// over the 8 corners against finite differences, and the jacobian error model with the
// measurement's own points (Measurement::points_o) reconstructing the exact error.
TEST(Jacobian, StackedOverATwoTagBundle) {
  FeatureModel bundle = FeatureModel::square(0.2);
  const SE3 g_ot = make_pose(Vec3(0.256066, 0, -0.106066), Vec3(0, 0.785398, 0));
  for (const auto& p : FeatureModel::square(0.2).points_o) bundle.points_o.push_back(g_ot * p);
  const SE3 g_bar = make_pose(Vec3(-0.1, 0.05, 2.0), Vec3(M_PI, 0, 0)) *
                    make_pose(Vec3::Zero(), Vec3(0.05, 0.1, 0.02));  // head-on, slightly turned
  const Eigen::MatrixXd J = image_jacobian(g_bar, bundle);
  ASSERT_EQ(J.rows(), 16);
  const Eigen::MatrixXd fd = finite_difference_jacobian(g_bar, bundle);
  for (int k = 0; k < 6; ++k) EXPECT_LT((J.col(k) - fd.col(k)).norm(), 1e-8) << "column " << k;
  // Rows 8..15 are the second tag's own Jacobian block (the stacking keeps the point order).
  FeatureModel second;
  second.points_o.assign(bundle.points_o.begin() + 4, bundle.points_o.end());
  EXPECT_LT((J.bottomRows(8) - image_jacobian(g_bar, second)).norm(), 1e-15);

  const Vec6 d = (Vec6() << 0.004, -0.003, 0.006, 0.003, -0.004, 0.002).finished();
  const SE3 g_true = g_bar * perturbation(d);
  Measurement z;
  z.delta = true;
  z.f = project(g_true, bundle);
  z.points_o = bundle.points_o;
  const ErrorModel& jac = error_models().find("jacobian");
  const Vec6 e = jac.error(g_bar, z, FeatureModel::square(0.2));  // (eq:eei) on all 8 points
  EXPECT_LT((e - E_R(g_bar.inverse() * g_true)).norm(), 0.05 * d.norm());
  EXPECT_LT((e - reconstruct_error(g_bar, z.f, bundle)).norm(), 1e-15);
  // Only the second tag seen: its 4 points.
  z.f = project(g_true, second);
  z.points_o = second.points_o;
  EXPECT_LT((jac.error(g_bar, z, FeatureModel::square(0.2)) - E_R(g_bar.inverse() * g_true)).norm(),
            0.05 * d.norm());
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
