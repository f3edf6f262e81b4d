// Results of an image run: estimates.csv, energies.csv, errors.csv and summary.json.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::run {

/// Position error [m] and orientation error [deg] between two poses.
struct PoseError {
  double position = 0.0;
  double orientation_deg = 0.0;
};
PoseError pose_error(const obs::SE3& estimate, const obs::SE3& reference);

/// The summary of target `target` (index in network.yaml's targets): settings, `target` (its
/// primary tag's id), per-camera final and time-averaged errors of the networked observer and
/// of each baseline against g*(t) (the average of the detecting cameras' fictitious target
/// poses) and against the true target pose, the epsilon-levels and the fraction of frames each
/// camera saw the target.
nlohmann::json run_summary(const sources::NetworkSource& source, const ImageRunSettings& options,
                           const ImageRunResult& result, size_t target);
/// The summary written to summary.json: run_summary(..., 0) for a single target; with several,
/// the run's keys once and `targets`, a list holding each target's own keys (target, cameras,
/// final, eps_*_last_quarter, centralized_pnp_average, target_max_step_deg).
nlohmann::json run_summary(const sources::NetworkSource& source, const ImageRunSettings& options,
                           const ImageRunResult& result);

/// Writes estimates.csv (frame,t,camera,delta,px,py,pz,rx,ry,rz), energies.csv
/// (frame,t,U_p,U_R, only frames with ground truth), errors.csv (frame,t and per camera the
/// networked observer's position [mm] and orientation [deg] error to g*) and summary.json, each
/// atomically. Several targets: each CSV has a `target` column (the primary tag's id) after
/// `t`, its rows target after target. `g_star_localisation` (`netvmo run --calibration`'s
/// block, calib::g_star_localisation_summary()), when given, is the summary's key of that name.
/// Returns the summary.
nlohmann::json write_run_outputs(
    const std::filesystem::path& dir, const sources::NetworkSource& source,
    const ImageRunSettings& options, const ImageRunResult& result,
    const std::optional<nlohmann::json>& g_star_localisation = std::nullopt);

}  // namespace netvmo::run
