// What the cameras' localisation error alone contributes to the distance between g* and the
// true target pose, propagated to first order from calibrate's covariances (calibrate.hpp).
//
// g* (eq:g_ave) averages the fictitious target poses g_wi g_io,true of the n detecting cameras:
// p* is their mean position, R* the projection of their summed rotations onto SO(3). A camera
// believed at g_wi = (R_i exp(hat(dtheta_i)), p_i + dp_i) puts its fictitious target at
//   p_i + dp_i + R_i exp(hat(dtheta_i)) p_io = p_fict,i + dp_i - hat(q_i) R_i dtheta_i + O(2),
//   q_i = R_i p_io (the target seen from the camera, in world axes),
// and turns its rotation by R_i dtheta_i (world axes). Averaging (the rotations all close):
//   dp* = (1/n) sum_i [I, -hat(q_i) R_i] e_i,   dtheta* = (1/n) sum_i [0, R_i] e_i,
// e_i = [dp_i; dtheta_i] ~ N(0, Sigma_i), independent across cameras (true for the map case;
// the moved-tag case's cross-covariances are left out). The predicted RMS distances are
// sqrt(trace) of the two 3x3 covariances.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::calib {

/// One detecting camera: its believed pose, its fictitious target position and its covariance.
struct GStarTerm {
  obs::SE3 g_wi = obs::SE3::Identity();
  obs::Vec3 p_fictitious = obs::Vec3::Zero();  ///< position of g_wi g_io,true
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

/// First-order covariance of g*'s position (top-left 3x3) and rotation (bottom-right, world
/// axes) caused by the cameras' localisation errors (the header's formula). Empty: zero.
Eigen::Matrix<double, 6, 6> g_star_covariance(const std::vector<GStarTerm>& terms);

/// Every camera's covariance in a calibration.json (netvmo calibrate), by camera id. Throws
/// InputError naming the file and the key when it is not one.
std::map<int, Eigen::Matrix<double, 6, 6>> read_calibration_covariances(
    const std::filesystem::path& file);

/// The summary block: per frame with g* and the true target pose, the distance |p* - p_true| and
/// the angle of R_true^T R*, measured, next to the predicted RMS of both from localisation alone;
/// the final frame's and the means over frames. Every camera of the run needs a covariance
/// (InputError naming the file and the camera otherwise). Target 0 (network.yaml's first).
nlohmann::json g_star_localisation_summary(const sources::World& world,
                                           const run::ImageRunResult& result,
                                           const std::map<int, Eigen::Matrix<double, 6, 6>>& cov,
                                           const std::string& source);

}  // namespace netvmo::calib
