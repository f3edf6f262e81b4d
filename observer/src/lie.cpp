#include "netvmo/observer/lie.hpp"

#include "lanes.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace netvmo::obs {
using kernel::kSmallAngle;  // lanes.hpp
namespace {
constexpr double kPi = 3.14159265358979323846;
// Within this distance of pi, sin(theta) is too small to recover the axis from sk(R).
constexpr double kNearPi = 1e-3;
}  // namespace

Mat3 exp_so3(const Vec3& w) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  double a, b;  // R = I + a hat(w) + b hat(w)^2
  if (t < kSmallAngle) {
    a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
    b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
  } else {
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t2;
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() + a * W + b * W * W;
}

Vec3 log_so3(const Mat3& R) {
  const double c = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const Vec3 s = vee(R);  // sin(theta) * xi
  const double sn = s.norm();
  const double theta = std::atan2(sn, c);
  if (theta < kSmallAngle) return s * (1.0 + theta * theta / 6.0);  // theta / sin(theta)
  if (theta < kPi - kNearPi) return s * (theta / sn);
  // Near pi: (R + R^T)/2 = cos(theta) I + (1 - cos(theta)) xi xi^T. Take the best-conditioned
  // column of xi xi^T and fix the sign of xi with sk(R), which is still reliable in direction.
  const Mat3 B = ((R + R.transpose()) * 0.5 - c * Mat3::Identity()) / (1.0 - c);
  int k = 0;
  B.diagonal().maxCoeff(&k);
  Vec3 xi = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
  xi.normalize();
  if (xi.dot(s) < 0.0) xi = -xi;
  return xi * theta;
}

Mat4 hat_se3(const Vec6& V) {
  Mat4 M = Mat4::Zero();
  M.topLeftCorner<3, 3>() = hat(V.tail<3>());
  M.topRightCorner<3, 1>() = V.head<3>();
  return M;
}

SE3 exp_se3(const Vec6& V) {
  SE3 g = SE3::Identity();
  Mat3 R;
  Vec3 p;
  exp_se3(V, R, p);
  g.linear() = R;
  g.translation() = p;
  return g;
}

void exp_se3(const Vec6& V, Mat3& R, Vec3& p) {
  kernel::exp_se3(V, R, p);  // written once for one camera and two (lanes.hpp)
}

Vec6 log_se3(const SE3& g) {
  const Vec3 w = log_so3(g.linear());
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  double d;  // inverse left Jacobian J^-1 = I - hat(w)/2 + d hat(w)^2
  if (t < kSmallAngle) {
    d = 1.0 / 12.0 + t2 / 720.0;
  } else {
    d = 1.0 / t2 - std::cos(0.5 * t) / std::sin(0.5 * t) / (2.0 * t);
  }
  const Mat3 W = hat(w);
  Vec6 V;
  V.head<3>() = (Mat3::Identity() - 0.5 * W + d * W * W) * g.translation();
  V.tail<3>() = w;
  return V;
}

Mat3 sk(const Mat3& R) {
  return (R - R.transpose()) * 0.5;
}

Vec6 E_R(const SE3& g) {
  Vec6 e;
  e.head<3>() = g.translation();
  e.tail<3>() = e_R(g.linear());
  return e;
}

double phi(const Mat3& R) {
  return 3.0 - R.trace();
}

double psi(const SE3& g) {
  return 0.5 * g.translation().squaredNorm() + phi(g.linear());
}

SE3 make_pose(const Vec3& p, const Vec3& xitheta) {
  SE3 g = SE3::Identity();
  g.linear() = exp_so3(xitheta);
  g.translation() = p;
  return g;
}

Mat3 project_to_so3(const Mat3& M) {
  Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

}  // namespace netvmo::obs
