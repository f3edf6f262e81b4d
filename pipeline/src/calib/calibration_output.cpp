// `netvmo calibrate`'s outputs: network.yaml, calibration.json (with the errors against the truth
// on rendered data), the residuals, cameras.csv and timestamps.csv, and the line per camera.
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "netvmo/pipeline/calib/calibrate.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::calib {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::vector<double> row(const obs::Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

// Error in the covariance's coordinates (header): [p_est - p_true; log(R_true^T R_est)].
obs::Vec6 pose_error(const obs::SE3& est, const obs::SE3& truth) {
  obs::Vec6 e;
  e.head<3>() = est.translation() - truth.translation();
  e.tail<3>() = obs::log_so3(truth.linear().transpose() * est.linear());
  return e;
}

json error_json(const obs::Vec6& e, const Mat6* cov) {
  json j = {{"error", std::vector<double>(e.data(), e.data() + 6)},
            {"position_mm", 1e3 * e.head<3>().norm()},
            {"orientation_deg", e.tail<3>().norm() * 180.0 / M_PI}};
  if (cov && cov->diagonal().minCoeff() > 0) j["d2"] = e.dot(cov->ldlt().solve(e));
  return j;
}

// On rendered data (truth_cameras.csv): each camera's error against the truth, and for the map
// case the naive per-frame solvePnP average's. Without a map the estimate lives in the frame the
// reference camera fixes: the truth is mapped into it (X_ref X_ref,true^-1), static cameras only.
void truth_errors(sources::Dataset& ds, const CalibrationResult& r, json& cameras) {
  const fs::path file = ds.dir / "truth_cameras.csv";
  if (!fs::exists(file)) return;
  std::map<int, obs::SE3> truth0;
  for (const auto& row : io::read_camera_truth_csv(file))
    if (row.frame <= 0) truth0[row.camera] = row.g_wi;
  // X_true of camera i: g_wi,true(0) B(0)^-1 (static: g_wi,true).
  const auto X_true = [&](size_t i) -> std::optional<obs::SE3> {
    const auto it = truth0.find(r.cameras[i].id);
    if (it == truth0.end()) return std::nullopt;
    return r.cameras[i].moving ? obs::SE3(it->second * ds.camera_pose(i, 0).inverse()) : it->second;
  };
  obs::SE3 frame = obs::SE3::Identity();
  if (!r.with_map) {
    for (size_t i = 0; i < r.cameras.size(); ++i)
      if (r.cameras[i].reference) {
        const auto t = X_true(i);
        if (!t) return;
        frame = r.cameras[i].X * t->inverse();
      }
  }
  for (size_t i = 0; i < r.cameras.size(); ++i) {
    const auto& c = r.cameras[i];
    const auto t = X_true(i);
    if (!c.ok || !t || (!r.with_map && c.moving)) continue;
    const obs::SE3 truth = frame * *t;
    cameras[i]["vs_truth"] =
        error_json(pose_error(c.X, truth), c.reference ? nullptr : &c.covariance);
    if (c.naive_pnp)
      cameras[i]["naive_pnp"]["vs_truth"] = error_json(pose_error(*c.naive_pnp, truth), nullptr);
  }
}

}  // namespace

void write_calibration(const fs::path& dir, sources::Dataset& ds, const CalibrationResult& r,
                       const io::NetworkConfig& calibrated) {
  io::write_file_atomic(dir / "network.yaml", io::network_yaml(calibrated));
  json j;
  j["case"] = r.with_map ? "map" : "moved_tag";
  j["perturbation"] =
      "X = (R exp(hat(dtheta)), p + dp); covariance of [dp (world, m); dtheta (camera frame, rad)]";
  if (!r.with_map) {
    j["sigma_px"] = r.sigma_px;
    j["moments"] = r.moments;
  }
  j["cameras"] = json::array();
  for (const auto& c : r.cameras) {
    json cj;
    cj["id"] = c.id;
    cj["ok"] = c.ok;
    if (!c.reason.empty()) cj["reason"] = c.reason;
    cj["moving"] = c.moving;
    if (c.reference) cj["reference"] = true;
    cj["images"] = c.images;
    cj["frames_seen"] = c.frames_seen;
    cj["observations"] = {{"used", c.observations_used},
                          {"rejected_front_end", c.rejected_front_end},
                          {"rejected_outlier", c.rejected_outlier}};
    cj["seconds"] = c.seconds;
    if (c.ok) {
      cj["p_wi"] = row(c.g_wi0.translation());
      cj["r_wi"] = row(obs::log_so3(c.g_wi0.linear()));
      if (c.moving) {
        cj["X"] = {{"p", row(c.X.translation())}, {"r", row(obs::log_so3(c.X.linear()))}};
      }
      cj["rms_px"] = c.rms_px;
      cj["frame_correlation"] = c.frame_correlation;
      cj["covariance_inflation"] = c.covariance_inflation;
      const obs::Vec6 sd = c.sigmas();
      cj["sigma"] = {{"p_m", row(sd.head<3>())}, {"theta_rad", row(sd.tail<3>())}};
      json cov = json::array();
      for (int a = 0; a < 6; ++a) {
        std::vector<double> rr;
        for (int b = 0; b < 6; ++b) rr.push_back(c.covariance(a, b));
        cov.push_back(rr);
      }
      cj["covariance"] = cov;
    }
    if (c.naive_pnp)
      cj["naive_pnp"] = {{"p_wi", row(c.naive_pnp->translation())},
                         {"r_wi", row(obs::log_so3(c.naive_pnp->linear()))}};
    j["cameras"].push_back(cj);
  }
  truth_errors(ds, r, j["cameras"]);
  io::write_file_atomic(dir / "calibration.json", j.dump(2) + "\n");
  for (const auto& c : r.cameras) {
    std::ostringstream csv;
    csv << "frame,tag,corner,du,dv,used\n";
    csv.precision(9);
    for (const auto& e : c.residuals)
      csv << e.frame << "," << e.tag << "," << e.corner << "," << e.du << "," << e.dv << ","
          << (e.used ? 1 : 0) << "\n";
    io::write_file_atomic(dir / ("residuals_cam_" + std::to_string(c.id) + ".csv"), csv.str());
  }
  // cameras.csv overrides network.yaml's poses in a dataset: when the input has one, so does
  // the output (every kept camera, every frame: X B(t), a static camera its pose).
  bool any_rows = false;
  for (const auto& c : ds.cameras) any_rows = any_rows || !c.poses.empty();
  if (any_rows) {
    std::ostringstream csv;
    csv << io::kCameraPosesHeader << "\n";
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
      const auto& c = r.cameras[i];
      if (!c.ok || calibrated.index_of(c.id) < 0) continue;
      for (int f = 0; f < ds.camera_frame_count(i); ++f) {
        const obs::SE3 g = c.moving ? obs::SE3(c.X * ds.camera_pose(i, f)) : c.X;
        csv << io::format_camera_pose_row(c.id, f, ds.frame_time(i, f), g) << "\n";
      }
    }
    io::write_file_atomic(dir / "cameras.csv", csv.str());
  }
  // timestamps.csv names cameras too: a camera left out (--keep-going) must leave it as well.
  bool any_times = false;
  for (const auto& c : ds.cameras) any_times = any_times || !c.times.empty();
  if (any_times && calibrated.cameras.size() < ds.cameras.size()) {
    std::ostringstream csv;
    csv << io::kTimestampsHeader << "\n";
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
      if (calibrated.index_of(r.cameras[i].id) < 0) continue;
      for (int f = 0; f < ds.camera_frame_count(i); ++f)
        if (const auto t = ds.listed_time(i, f))
          csv << io::format_timestamp_row(r.cameras[i].id, f, *t) << "\n";
    }
    io::write_file_atomic(dir / "timestamps.csv", csv.str());
  }
}

std::string camera_line(const CameraResult& c) {
  char b[512];
  if (!c.ok) {
    std::snprintf(b, sizeof b, "camera %d: not calibrated: %s", c.id, c.reason.c_str());
    return b;
  }
  const obs::Vec3 p = c.g_wi0.translation(), r = obs::log_so3(c.g_wi0.linear());
  const obs::Vec6 sd = c.sigmas();
  std::snprintf(b, sizeof b,
                "camera %d: p_wi [%.4f, %.4f, %.4f] r_wi [%.4f, %.4f, %.4f]%s, %d tag "
                "observations in %d of %d images (%d refused by the front end, %d outliers), "
                "RMS %.3f px, sd %.2f mm / %.3f deg%s",
                c.id, p.x(), p.y(), p.z(), r.x(), r.y(), r.z(), c.moving ? " (at frame 0)" : "",
                c.observations_used, c.frames_seen, c.images, c.rejected_front_end,
                c.rejected_outlier, c.rms_px, 1e3 * sd.head<3>().norm(),
                sd.tail<3>().norm() * 180.0 / M_PI, c.reference ? " (reference: held fixed)" : "");
  return b;
}

}  // namespace netvmo::calib
