// Per-camera pose of the tag from its four corners with ViSP (vpPose).
//
// Used to initialise g_bar_i at the first detection, for the `pnp` error model
// e_i = E_R(g_bar_i^-1 g_io,PnP), and as the independent per-camera baseline.
#pragma once

#include <Eigen/Core>
#include <optional>

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

/// The `pnp` error model: e_i = E_R(g_bar^-1 g_io,PnP).
inline obs::Vec6 pnp_error(const obs::SE3& g_bar, const obs::SE3& g_io_pnp) {
  return obs::E_R(g_bar.inverse() * g_io_pnp);
}

}  // namespace netvmo::frontend
