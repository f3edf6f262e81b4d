// Perspective projection of the target's feature points and the image Jacobian that
// reconstructs the estimation error from image measurements.
#pragma once

#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::obs {

/// The target's m >= 4 feature points p_ol in the object frame, and the focal length lambda.
/// The pipeline uses undistorted normalized image coordinates, i.e. lambda = 1.
struct FeatureModel {
  std::vector<Vec3> points_o;  ///< p_ol, l = 1..m (object frame, metres)
  double lambda = 1.0;         ///< focal length of (eq:visual_mea); 1 for normalized coordinates

  /// A square of side s centred at the origin in the z = 0 plane. Object frame: x to the right
  /// of the printed tag, y up, z out of the printed face. Corners in libapriltag's detection
  /// order (counter-clockwise seen from the front, starting bottom-left):
  /// (-s/2, -s/2), (s/2, -s/2), (s/2, s/2), (-s/2, s/2).
  static FeatureModel square(double side, double lambda = 1.0);
};

/// f = [f_1; ...; f_m], f_l = lambda / z_l [x_l; y_l], p_l = g_io p_ol (eq:visual_mea).
/// Throws std::domain_error if a point is not strictly in front of the camera.
Eigen::VectorXd project(const SE3& g_io, const FeatureModel& model);

/// Image Jacobian J(g_bar) (2m x 6): f(g_bar * g_e) = f(g_bar) + J(g_bar) E_R(g_e) + O(|E_R|^2),
/// the linearisation behind (eq:eei). Row block l is
///   lambda/z_l [1 0 -x_l/z_l; 0 1 -y_l/z_l] R_bar [I_3, -hat(p_ol)].
Eigen::MatrixXd image_jacobian(const SE3& g_bar, const FeatureModel& model);

/// e = J^dagger(g_bar) (f - f_bar(g_bar)) (eq:eei): the estimation error vector reconstructed
/// from a measured feature vector f (2m).
Vec6 reconstruct_error(const SE3& g_bar, const Eigen::VectorXd& f, const FeatureModel& model);

}  // namespace netvmo::obs
