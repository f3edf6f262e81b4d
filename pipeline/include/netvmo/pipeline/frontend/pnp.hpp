// Per-camera pose of the tag from its four corners with ViSP (vpPose).
//
// Used to initialise g_bar_i at the first detection, for the `pnp` error model
// e_i = E_R(g_bar_i^-1 g_io,PnP), and as the independent per-camera baseline.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/observer/lie.hpp"

namespace netvmo::frontend {

struct PnpResult {
  obs::SE3 g_io = obs::SE3::Identity();  ///< object (tag) -> camera; ViSP's cMo
  double residual = 0.0;                 ///< RMS reprojection error in normalized coordinates
};

/// Pose of the object in the camera from m >= 4 undistorted normalized image points
/// f = [x0,y0,...] matching model.points_o index by index (lambda must be 1). Candidates:
/// ViSP's Lagrange and Dementhon linear poses and OpenCV's two IPPE planar solutions, each
/// refined by ViSP's virtual visual servoing; the one with the smallest residual wins (this
/// resolves the planar two-fold ambiguity whenever the image disambiguates it).
/// Returns nullopt if every candidate fails or places the points behind the camera.
std::optional<PnpResult> pnp_pose(const Eigen::VectorXd& f, const obs::FeatureModel& model);

/// A pose's 6x6 covariance in ROS's PoseWithCovariance order and convention for a pose given in
/// its header's frame: (x, y, z, rotation about X, Y, Z), the perturbation (dp, dphi) with
/// p = p_hat + dp and R = exp(hat(dphi)) R_hat, all in that frame's axes.
using PoseCovariance = Eigen::Matrix<double, 6, 6>;

/// First-order covariance of pnp_pose's g_io (the tag in the camera frame, PoseCovariance's
/// convention) from the covariance `f_cov` (2m x 2m) of the normalized points f. pnp_pose
/// minimises the unweighted squared residual |f - pi(g_io p_ol)|^2, so dtheta = A^+ df with A the
/// 2m x 6 Jacobian of the projections pi(R p_ol + p) with respect to (dp, dphi): row block l is
/// P_l [I_3, -hat(R p_ol)], P_l = 1/z_l [1 0 -x_l/z_l; 0 1 -y_l/z_l] at the camera point
/// (x_l, y_l, z_l); the covariance is the sandwich (A^T A)^-1 A^T f_cov A (A^T A)^-1 (equal to
/// (A^T f_cov^-1 A)^-1 when f_cov is a multiple of the identity). Throws std::invalid_argument
/// on sizes that do not match, std::domain_error for a point not in front of the camera.
PoseCovariance pnp_covariance(const obs::SE3& g_io, const std::vector<obs::Vec3>& points_o,
                              const Eigen::MatrixXd& f_cov);

/// The Jacobian A of pnp_covariance (exposed for its test against finite differences).
Eigen::MatrixXd pnp_jacobian(const obs::SE3& g_io, const std::vector<obs::Vec3>& points_o);

/// The `pnp` error model: e_i = E_R(g_bar^-1 g_io,PnP).
inline obs::Vec6 pnp_error(const obs::SE3& g_bar, const obs::SE3& g_io_pnp) {
  return obs::E_R(g_bar.inverse() * g_io_pnp);
}

}  // namespace netvmo::frontend
