// The calibration's bundle adjustment (internal to calib/): the tag observations, the
// least-squares problem over camera poses X_i and body poses Y_k with Ceres, its solve / reject
// rounds and the cameras' covariances, and the initial poses from PnP (calibrate.hpp has the
// model, docs/calibration.md the derivations).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/calib/calibrate.hpp"

namespace netvmo::calib::detail {

/// A pose and its perturbation (calibrate.hpp): (R exp(hat(dtheta)), p + dp),
/// delta = [dp; dtheta].
obs::SE3 perturbed(const obs::SE3& g, const double* delta);

/// One tag seen in one image: its 4 corners (undistorted normalized) and its corner points in
/// the body frame b (the world for a map; the moved body's frame o otherwise).
struct TagSeen {
  size_t cam = 0;
  int frame = 0;
  size_t body = 0;  ///< moment index (no-map case); 0 for a map
  int tag = 0;
  obs::SE3 B_inv = obs::SE3::Identity();  ///< B_i(t)^-1 (identity for a static camera)
  std::array<obs::Vec3, 4> P;
  std::array<Eigen::Vector2d, 4> m;
  bool used = true;
};

/// The least-squares problem over cameras X_i and bodies Y_k (a map: one fixed body, the
/// world), each pose with its perturbation (dc, db) while Ceres solves.
struct Ba {
  std::vector<obs::SE3> X, Y;
  std::vector<std::array<double, 6>> dc, db;
  std::vector<bool> cam_fixed, body_fixed;
  std::vector<TagSeen> seen;
  std::vector<double> fx, fy;  ///< per camera

  /// Corner k of observation o's residual [undistorted px] at the current poses (plus deltas),
  /// camera o.cam at X_alt when given.
  Eigen::Vector2d residual(const TagSeen& o, int k, const obs::SE3* X_alt = nullptr) const;
  /// Folds the deltas into the poses.
  void fold();
};

/// Solve / reject rounds (calibrate.hpp: reject_sigmas, reject_min_px, max_rounds): after each
/// solve, an observation with a corner residual above max(reject_sigmas RMS, reject_min_px) is
/// no longer used, until none is.
void solve(Ba& ba, const CalibrationSettings& s);

/// Ceres' covariance of the free camera blocks, unit corner noise: (J^T J)^-1 over the used
/// observations without the loss (the outliers are gone; Huber's weight is 1 on the inliers).
/// ok[i]: camera i's block was computed.
std::vector<Mat6> camera_covariances(Ba& ba, std::vector<bool>& ok);

/// Huber cost of camera i's observations (bodies at their current poses; only the bodies
/// body_known marks, when given) with pose X_i = X.
double robust_cost(const Ba& ba, size_t i, const obs::SE3& X, double huber,
                   const std::vector<bool>* body_known = nullptr);

/// Per-image groups of the observations ((camera, frame) -> observations), in that order.
std::map<std::pair<size_t, int>, std::vector<const TagSeen*>> by_image(const Ba& ba);

/// PnP (frontend::pnp_pose) of the points of `obs` (one image's tags): g_ib, pose of the body
/// frame in the camera.
std::optional<obs::SE3> image_pnp(const std::vector<const TagSeen*>& obs);

/// The naive per-frame pose: OpenCV solvePnP (SQPNP) on one image's corners, g_ib.
std::optional<obs::SE3> naive_pnp(const std::vector<const TagSeen*>& obs);

/// The chordal mean of poses: mean position, rotation the closest to the mean matrix.
obs::SE3 mean_pose(const std::vector<obs::SE3>& g);

}  // namespace netvmo::calib::detail
