#include "netvmo/pipeline/run/trajectories.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;

std::string tum_line(double t, const obs::SE3& g_wo) {
  Eigen::Quaterniond q(g_wo.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // q and -q are one rotation: one form of it
  const obs::Vec3 p = g_wo.translation();
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f", t, p.x(), p.y(), p.z(),
                q.x(), q.y(), q.z(), q.w());
  return buf;
}

namespace {

struct Pending {
  TrajectoryFile file;
  std::string text;
  double last_t = 0.0;
  std::string last_where;
};

// Appends a pose to a trajectory; its time must come after the trajectory's last.
void append(Pending& p, double t, const obs::SE3& g, const std::string& where) {
  if (p.file.poses > 0 && !(t > p.last_t)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": t: %.9g s is not after the previous pose's %.9g s (%s)", t,
                  p.last_t, p.last_where.c_str());
    throw InputError(where + buf);
  }
  p.text += tum_line(t, g) + "\n";
  ++p.file.poses;
  p.last_t = t;
  p.last_where = where;
}

// The results' clock, from their summary.json: where a dataset time t of target.csv's row of
// frame f falls on it. time_origin_s a number: t less it (cameras on their own clocks); null:
// f / fps (one clock). Without the file or the key (simulate's results, or written before the
// key existed), t itself.
std::function<double(int, double)> results_clock(const fs::path& results) {
  const auto as_is = [](int, double t) { return t; };
  const fs::path file = results / "summary.json";
  std::ifstream in(file);
  if (!in) return as_is;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) throw InputError(file.string() + ": not a JSON object");
  if (!j.contains("time_origin_s")) return as_is;
  const nlohmann::json& v = j["time_origin_s"];
  if (v.is_null()) {
    const nlohmann::json fps = j.value("fps", nlohmann::json());
    if (!fps.is_number() || !(fps.get<double>() > 0))
      throw InputError(file.string() +
                       ": fps: expected a number > 0 (time_origin_s is null: t = "
                       "frame / fps), got " +
                       fps.dump());
    const double rate = fps.get<double>();
    return [rate](int frame, double) { return frame / rate; };
  }
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw InputError(file.string() + ": time_origin_s: expected a number of seconds or null, got " +
                     v.dump());
  const double origin = v.get<double>();
  return [origin](int, double t) { return t - origin; };
}

std::string prefix(int target) {
  return target < 0 ? std::string() : "target_" + std::to_string(target) + "_";
}

}  // namespace

std::vector<TrajectoryFile> write_trajectories(const fs::path& results,
                                               const std::optional<fs::path>& dataset,
                                               const fs::path& out) {
  const fs::path estimates = results / "estimates.csv";
  // By (target, camera) in the order of the file's targets, then by camera id.
  std::vector<int> targets;  // in the order of the file (the first is the primary target)
  std::map<std::pair<size_t, int>, Pending> cameras;
  for (const io::EstimateRow& r : io::read_estimates_csv(estimates)) {
    size_t j = 0;
    while (j < targets.size() && targets[j] != r.target) ++j;
    if (j == targets.size()) targets.push_back(r.target);
    Pending& p = cameras[{j, r.camera}];
    p.file.target = r.target;
    p.file.camera = r.camera;
    if (r.g_w) append(p, r.t, *r.g_w, estimates.string() + ":" + std::to_string(r.line));
  }
  if (targets.empty()) throw InputError(estimates.string() + ": no rows");
  std::vector<Pending> files;
  for (auto& [key, p] : cameras) {
    if (p.file.poses == 0) continue;  // never an estimate
    p.file.name = prefix(p.file.target) + "cam_" + std::to_string(p.file.camera) + ".txt";
    files.push_back(std::move(p));
  }
  // The truth on the results' clock (target.csv keeps the dataset's times).
  const auto clock = results_clock(results);
  if (dataset)
    for (size_t j = 0; j < targets.size(); ++j) {
      const fs::path file = *dataset / io::target_truth_file(targets[j], j == 0);
      if (j > 0 && !fs::exists(file)) continue;  // that target's truth is not known
      Pending p;
      p.file.target = targets[j];
      p.file.name = prefix(targets[j]) + "truth.txt";
      for (const io::TargetTruthRow& r : io::read_target_csv(file))
        append(p, clock(r.frame, r.t), r.g_wo,
               file.string() + ": frame " + std::to_string(r.frame));
      files.push_back(std::move(p));
    }
  std::vector<TrajectoryFile> written;
  for (const Pending& p : files) {
    io::write_file_atomic(out / p.file.name, p.text);
    written.push_back(p.file);
  }
  return written;
}

}  // namespace netvmo::run
