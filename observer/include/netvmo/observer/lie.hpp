// SO(3) / SE(3) maths in the paper's conventions.
//
// Equation labels refer to the paper "Vision-Based Cooperative Estimation of Averaged 3D
// Target Pose under Imperfect Visibility" (Hatanaka, Nishi, Fujita); e.g. (eq:ER).
//
// Conventions (docs/extending.md, "Layout and conventions"):
//  - g_ab maps coordinates in frame b to frame a, homogeneous [R p; 0 1].
//  - Twists and error vectors are ordered [v; w] (position first), as in E_R(g) = [p; e_R(R)].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace netvmo::obs {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using SE3 = Eigen::Isometry3d;

/// a^ such that hat(a) * b = a x b.
inline Mat3 hat(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a.z(), a.y(),  //
      a.z(), 0.0, -a.x(),   //
      -a.y(), a.x(), 0.0;
  return S;
}
/// Inverse of hat for a skew-symmetric matrix (reads the skew part only).
inline Vec3 vee(const Mat3& S) {
  return Vec3(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1)) * 0.5;
}

/// Rodrigues' formula e^{hat(w)}; exact Taylor branch near w = 0.
Mat3 exp_so3(const Vec3& w);
/// Rotation vector xi*theta with theta in [0, pi]; robust near 0 and near pi.
Vec3 log_so3(const Mat3& R);

/// Pose from a position and a rotation vector xi*theta.
SE3 make_pose(const Vec3& p, const Vec3& xitheta);
/// Rotation vector of a pose's rotation.
inline Vec3 rotvec(const SE3& g) {
  return log_so3(g.linear());
}

/// 4x4 twist matrix hat(V) = [hat(w) v; 0 0] for V = [v; w].
Mat4 hat_se3(const Vec6& V);
/// e^{hat(V)} for V = [v; w] (closed form with the left Jacobian of SO(3)).
SE3 exp_se3(const Vec6& V);
/// The same, as its rotation R and translation p (no 4x4 matrix; one sine and cosine).
void exp_se3(const Vec6& V, Mat3& R, Vec3& p);
/// Inverse of exp_se3 for rotation angles in [0, pi].
Vec6 log_se3(const SE3& g);

/// sk(R) = (R - R^T) / 2 (eq:ER).
Mat3 sk(const Mat3& R);
/// e_R(R) = sk(R)^vee (eq:ER); equals xi*sin(theta) for R = e^{hat(xi) theta}.
inline Vec3 e_R(const Mat3& R) {
  return vee(R);
}
/// E_R(g) = [p; e_R(R)] (eq:ER).
Vec6 E_R(const SE3& g);

/// phi(R) = 1/2 ||I - R||_F^2 = tr(I - R) (eq:phi).
double phi(const Mat3& R);
/// psi(g) = 1/2 ||I - g||_F^2 = 1/2 ||p||^2 + phi(R) (eq:psi).
double psi(const SE3& g);

/// Closest rotation (Frobenius norm) to an arbitrary 3x3 matrix, via SVD with det = +1.
Mat3 project_to_so3(const Mat3& M);

}  // namespace netvmo::obs
