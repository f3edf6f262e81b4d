// First-order propagation of the calibration's covariances into g* (g_star_uncertainty.hpp).
#include "netvmo/pipeline/calib/g_star_uncertainty.hpp"

#include <cmath>
#include <fstream>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::calib {
using Mat6 = Eigen::Matrix<double, 6, 6>;
using json = nlohmann::json;

Mat6 g_star_covariance(const std::vector<GStarTerm>& terms) {
  Mat6 out = Mat6::Zero();
  if (terms.empty()) return out;
  const double n = static_cast<double>(terms.size());
  for (const auto& t : terms) {
    // (eq:g_ave) averaged to first order: d(p*, theta*) = (1/n) sum_i A_i e_i.
    const obs::Mat3 R = t.g_wi.linear();
    const obs::Vec3 q = t.p_fictitious - t.g_wi.translation();
    Mat6 A = Mat6::Zero();
    A.block<3, 3>(0, 0) = obs::Mat3::Identity();
    A.block<3, 3>(0, 3) = -obs::hat(q) * R;
    A.block<3, 3>(3, 3) = R;
    out += A * t.covariance * A.transpose() / (n * n);
  }
  return out;
}

std::map<int, Mat6> read_calibration_covariances(const std::filesystem::path& file) {
  std::ifstream f(file);
  if (!f) throw InputError(file.string() + ": cannot be read (give netvmo calibrate's output)");
  json j;
  try {
    j = json::parse(f);
  } catch (const json::exception& e) {
    throw InputError(file.string() + ": not JSON (" + e.what() + ")");
  }
  std::map<int, Mat6> out;
  if (!j.contains("cameras") || !j["cameras"].is_array())
    throw InputError(file.string() + ": cameras: missing (not a calibration.json)");
  for (size_t k = 0; k < j["cameras"].size(); ++k) {
    const auto& c = j["cameras"][k];
    const std::string where = file.string() + ": cameras[" + std::to_string(k) + "]";
    try {
      if (!c.at("ok").get<bool>()) continue;
      const auto& m = c.at("covariance");
      Mat6 cov;
      if (m.size() != 6) throw InputError(where + ".covariance: expected 6 rows of 6 numbers");
      for (int a = 0; a < 6; ++a) {
        if (m[size_t(a)].size() != 6)
          throw InputError(where + ".covariance: expected 6 rows of 6 numbers");
        for (int b = 0; b < 6; ++b) cov(a, b) = m[size_t(a)][size_t(b)].get<double>();
      }
      if (!cov.allFinite()) throw InputError(where + ".covariance: not finite");
      out[c.at("id").get<int>()] = cov;
    } catch (const json::exception& e) {
      throw InputError(where + ": " + e.what());
    }
  }
  return out;
}

json g_star_localisation_summary(const sources::World& world, const run::ImageRunResult& result,
                                 const std::map<int, Mat6>& cov, const std::string& source) {
  const auto& net = world.network();
  for (const auto& c : net.cameras)
    if (!cov.count(c.id))
      throw InputError(source + ": no covariance for camera " + std::to_string(c.id) +
                       " of the run (calibrate it, or run without --calibration)");
  double sum_meas_p = 0, sum_meas_r = 0, sum_pred_p = 0, sum_pred_r = 0;
  int frames = 0;
  json last;
  for (const auto& r : result.history) {
    if (!r.g_star || !r.g_wo_true) continue;
    std::vector<GStarTerm> terms;
    for (size_t i = 0; i < r.cameras.size(); ++i) {
      const auto& c = r.cameras[i];
      if (!c.delta || !c.fictitious_w) continue;
      terms.push_back({world.camera_believed(i, r.frame), c.fictitious_w->translation(),
                       cov.at(net.cameras[i].id)});
    }
    const Mat6 S = g_star_covariance(terms);
    const double pred_p = std::sqrt(S.block<3, 3>(0, 0).trace());
    const double pred_r = std::sqrt(S.block<3, 3>(3, 3).trace());
    const double meas_p = (r.g_star->translation() - r.g_wo_true->translation()).norm();
    const double meas_r =
        obs::log_so3(r.g_wo_true->linear().transpose() * r.g_star->linear()).norm();
    sum_meas_p += meas_p, sum_meas_r += meas_r, sum_pred_p += pred_p, sum_pred_r += pred_r;
    ++frames;
    last = {{"frame", r.frame},
            {"cameras", terms.size()},
            {"measured_position_m", meas_p},
            {"predicted_rms_position_m", pred_p},
            {"measured_orientation_deg", meas_r * 180.0 / M_PI},
            {"predicted_rms_orientation_deg", pred_r * 180.0 / M_PI}};
  }
  json s;
  s["calibration"] = source;
  s["what"] =
      "distance between g* (eq:g_ave) and the true target pose: measured, and the RMS predicted "
      "from the cameras' localisation covariances alone (first order, cameras independent)";
  s["frames"] = frames;
  if (frames == 0) return s;
  s["final"] = last;
  s["mean"] = {{"measured_position_m", sum_meas_p / frames},
               {"predicted_rms_position_m", sum_pred_p / frames},
               {"measured_orientation_deg", sum_meas_r / frames * 180.0 / M_PI},
               {"predicted_rms_orientation_deg", sum_pred_r / frames * 180.0 / M_PI}};
  return s;
}

}  // namespace netvmo::calib
