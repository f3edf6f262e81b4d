// SO(3)/SE(3) maths against closed forms and an independent matrix exponential.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "netvmo/observer/lie.hpp"

using namespace netvmo::obs;

namespace {
constexpr double kPi = 3.14159265358979323846;

Vec3 random_axis(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}
}  // namespace

TEST(Lie, HatIsCrossProductAndVeeInvertsIt) {
  const Vec3 a(0.3, -1.2, 2.5), b(-0.7, 0.4, 1.1);
  EXPECT_TRUE((hat(a) * b).isApprox(a.cross(b)));
  EXPECT_TRUE(vee(hat(a)).isApprox(a));
  EXPECT_TRUE((hat(a) + hat(a).transpose()).isZero());
}

TEST(Lie, ExpSO3MatchesAngleAxis) {
  std::mt19937 rng(1);
  for (double theta : {1e-12, 1e-7, 1e-4, 0.3, 1.0, 2.5, kPi - 1e-6, kPi}) {
    const Vec3 axis = random_axis(rng);
    const Mat3 R = exp_so3(axis * theta);
    const Mat3 ref = Eigen::AngleAxisd(theta, axis).toRotationMatrix();
    EXPECT_LT((R - ref).norm(), 1e-14) << "theta=" << theta;
    EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  }
}

TEST(Lie, LogSO3InvertsExpIncludingNearZeroAndNearPi) {
  std::mt19937 rng(2);
  for (double theta : {0.0, 1e-12, 1e-8, 1e-5, 1e-4, 2e-4, 0.1, 1.0, 2.0, 3.0, kPi - 1e-2,
                       kPi - 1e-3, kPi - 1e-4, kPi - 1e-6, kPi - 1e-9}) {
    for (int k = 0; k < 20; ++k) {
      const Vec3 w = random_axis(rng) * theta;
      const Vec3 back = log_so3(exp_so3(w));
      EXPECT_LT((back - w).norm(), 1e-11) << "theta=" << theta;
    }
  }
}

TEST(Lie, LogSO3AtExactlyPiGivesAnAngleOfPi) {
  for (const Vec3& axis :
       {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 0).normalized()}) {
    const Mat3 R = Eigen::AngleAxisd(kPi, axis).toRotationMatrix();
    const Vec3 w = log_so3(R);
    EXPECT_NEAR(w.norm(), kPi, 1e-12);
    EXPECT_NEAR(std::abs(w.normalized().dot(axis)), 1.0, 1e-12);
    EXPECT_LT((exp_so3(w) - R).norm(), 1e-12);
  }
}

TEST(Lie, ExpSE3MatchesMatrixExponentialOfTwist) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double theta : {0.0, 1e-6, 0.5, 2.0, 3.1}) {
    Vec6 V;
    V.head<3>() = Vec3(u(rng), u(rng), u(rng));
    V.tail<3>() = random_axis(rng) * theta;
    const Mat4 ref = hat_se3(V).exp();
    EXPECT_LT((exp_se3(V).matrix() - ref).norm(), 1e-12) << "theta=" << theta;
  }
}

TEST(Lie, LogSE3InvertsExpSE3) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (double theta : {0.0, 1e-9, 1e-5, 0.7, 2.9, kPi - 1e-5}) {
    Vec6 V;
    V.head<3>() = Vec3(u(rng), u(rng), u(rng));
    V.tail<3>() = random_axis(rng) * theta;
    EXPECT_LT((log_se3(exp_se3(V)) - V).norm(), 1e-8) << "theta=" << theta;
  }
}

TEST(Lie, ERIsXiSinThetaAndPositionFirst) {
  std::mt19937 rng(5);
  for (double theta : {0.0, 0.2, 1.3, 2.8}) {
    const Vec3 xi = random_axis(rng);
    const Vec3 p(0.1, -0.2, 0.3);
    const SE3 g = make_pose(p, xi * theta);
    const Vec6 e = E_R(g);
    EXPECT_TRUE(e.head<3>().isApprox(p));
    EXPECT_LT((e.tail<3>() - xi * std::sin(theta)).norm(), 1e-14);  // (eq:ER)
    EXPECT_LT((hat(e_R(g.linear())) - sk(g.linear())).norm(), 1e-14);
    // e_R(R^T) = -e_R(R)
    EXPECT_LT((e_R(g.linear().transpose()) + e_R(g.linear())).norm(), 1e-14);
  }
}

TEST(Lie, PhiAndPsiMatchTheirFrobeniusDefinitions) {
  std::mt19937 rng(6);
  for (double theta : {0.0, 0.4, 1.9, kPi}) {
    const SE3 g = make_pose(Vec3(0.3, 0.5, -1.0), random_axis(rng) * theta);
    const Mat3 R = g.linear();
    EXPECT_NEAR(phi(R), 0.5 * (Mat3::Identity() - R).squaredNorm(), 1e-13);  // (eq:phi)
    EXPECT_NEAR(phi(R), 2.0 * (1.0 - std::cos(theta)), 1e-13);
    EXPECT_NEAR(psi(g), 0.5 * (Mat4::Identity() - g.matrix()).squaredNorm(), 1e-13);  // (eq:psi)
  }
}

TEST(Lie, ProjectToSO3RecoversRotationAndIsClosest) {
  const Mat3 R = exp_so3(Vec3(0.3, -0.5, 0.9));
  EXPECT_LT((project_to_so3(3.7 * R) - R).norm(), 1e-12);
  Mat3 M = R;
  M(0, 1) += 0.05;
  const Mat3 P = project_to_so3(M);
  EXPECT_NEAR(P.determinant(), 1.0, 1e-12);
  // Closest: nearby rotations are no closer to M.
  for (int a = 0; a < 3; ++a) {
    Vec3 d = Vec3::Zero();
    d[a] = 1e-3;
    EXPECT_GE((P * exp_so3(d) - M).norm(), (P - M).norm());
    EXPECT_GE((P * exp_so3(-d) - M).norm(), (P - M).norm());
  }
}
