#include "netvmo/pipeline/sources/network_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;

namespace {

std::string fmt(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

class DatasetSource final : public NetworkSource {
 public:
  DatasetSource(const fs::path& dir, std::optional<int> only_camera, bool keep_going,
                const fs::path& shown_as)
      : ds_(open_dataset(dir, only_camera, keep_going)),
        name_(shown_as.empty() ? dir.string() : shown_as.string()) {
    const fs::path cams = dir / "truth_cameras.csv";
    targets_.resize(ds_.network.targets.size());
    if (fs::exists(dir / "target.csv") && fs::exists(cams)) {
      for (size_t j = 0; j < targets_.size(); ++j) {
        const fs::path file = dir / io::target_truth_file(ds_.network, j);
        if (j > 0 && !fs::exists(file)) continue;  // that target's truth is not known
        TargetTruth& tt = targets_[j];
        for (const auto& r : io::read_target_csv(file)) {
          tt.by_frame[r.frame] = r.g_wo;
          if (tt.times.empty() || r.t > tt.times.back()) {  // by time, for _at
            tt.times.push_back(r.t);
            tt.poses.push_back(r.g_wo);
          }
        }
      }
      // Per frame, or one static pose per camera (frame -1, older datasets).
      std::map<int, std::vector<obs::SE3>> by_id;
      std::map<int, bool> fixed;
      for (const auto& r : io::read_camera_truth_csv(cams)) {
        by_id[r.camera].push_back(r.g_wi);
        fixed[r.camera] = r.frame < 0;
      }
      for (const auto& c : ds_.network.cameras) {
        const auto it = by_id.find(c.id);
        if (it == by_id.end())
          throw InputError(cams.string() + ": no row for camera " + std::to_string(c.id) +
                           " of network.yaml");
        camera_truth_.push_back({it->second, fixed[c.id]});
      }
    }
    // cameras.csv says something network.yaml does not: a pose other than network.yaml's
    // (a rendered static camera's rows hold network.yaml's numbers, written the same way).
    for (size_t i = 0; i < ds_.cameras.size() && !moving_; ++i)
      for (const auto& g : ds_.cameras[i].poses)
        moving_ = moving_ || !g.isApprox(ds_.network.cameras[i].g_wi, 0.0);
  }
  const io::NetworkConfig& network() const override { return ds_.network; }
  const io::Calibration& calibration(size_t i) const override { return ds_.cameras.at(i).calib; }
  int frame_count() const override { return ds_.frame_count; }
  cv::Mat read(size_t i, int frame) override { return ds_.read(i, frame); }
  std::optional<obs::SE3> target_truth(int frame, size_t target) const override {
    const auto& by_frame = targets_.at(target).by_frame;
    const auto it = by_frame.find(frame);
    if (it == by_frame.end()) return std::nullopt;
    return it->second;
  }
  std::optional<obs::SE3> camera_truth(size_t i, int frame) const override {
    if (i >= camera_truth_.size()) return std::nullopt;
    const auto& [poses, fixed] = camera_truth_[i];
    if (fixed) return poses.front();
    if (frame < 0 || static_cast<size_t>(frame) >= poses.size()) return std::nullopt;
    return poses[static_cast<size_t>(frame)];
  }
  obs::SE3 camera_believed(size_t i, int frame) const override { return ds_.camera_pose(i, frame); }
  bool cameras_move() const override { return moving_; }
  std::vector<std::string> warnings() const override { return ds_.warnings; }
  std::vector<std::string> notes() const override { return ds_.notes; }
  int camera_frame_count(size_t i) const override { return ds_.camera_frame_count(i); }
  std::optional<double> listed_time(size_t i, int frame) const override {
    return ds_.listed_time(i, frame);
  }
  std::string name() const override { return name_; }
  // target.csv's times have 6 decimals: a time within half of that is the row's.
  std::optional<obs::SE3> target_truth_at(double t, size_t target) const override {
    const TargetTruth& tt = targets_.at(target);
    return pose_at(tt.times, tt.poses, t, 5e-7);
  }
  std::optional<obs::SE3> camera_truth_at(size_t i, double t) const override {
    if (i >= camera_truth_.size()) return std::nullopt;
    const auto& [poses, fixed] = camera_truth_[i];
    if (fixed) return poses.front();
    return pose_at(image_times(i, poses.size()), poses, t, 1e-9);
  }
  obs::SE3 camera_believed_at(size_t i, double t) const override {
    const auto& poses = ds_.cameras.at(i).poses;
    if (poses.empty()) return ds_.network.cameras.at(i).g_wi;
    const auto times = image_times(i, poses.size());
    // Held before the first and after the last image, like camera_believed.
    return *pose_at(times, poses, std::clamp(t, times.front(), times.back()), 1e-9);
  }

 private:
  std::vector<double> image_times(size_t i, size_t n) const {
    std::vector<double> t;
    for (size_t k = 0; k < n; ++k) t.push_back(ds_.frame_time(i, static_cast<int>(k)));
    return t;
  }

  Dataset ds_;
  std::string name_;  // name(): the dataset folder, or what it is shown as
  struct TargetTruth {
    std::map<int, obs::SE3> by_frame;
    std::vector<double> times;  ///< the file's rows in time order
    std::vector<obs::SE3> poses;
  };
  std::vector<TargetTruth> targets_;  ///< per target of network.yaml
  /// Per camera: its true poses by frame, or (flag set) one static pose.
  std::vector<std::pair<std::vector<obs::SE3>, bool>> camera_truth_;
  bool moving_ = false;
};

}  // namespace

std::optional<obs::SE3> pose_at(const std::vector<double>& times,
                                const std::vector<obs::SE3>& poses, double t, double tol) {
  if (times.empty() || t < times.front() - tol || t > times.back() + tol) return std::nullopt;
  const size_t hi =
      static_cast<size_t>(std::lower_bound(times.begin(), times.end(), t - tol) - times.begin());
  if (hi == times.size()) return poses.back();
  if (std::abs(times[hi] - t) <= tol || hi == 0) return poses[hi];
  const size_t lo = hi - 1;
  const double s = (t - times[lo]) / (times[hi] - times[lo]);
  // The geodesic between the two poses (the renderer's keyframe interpolation).
  return obs::SE3(poses[lo] * obs::exp_se3(s * obs::log_se3(poses[lo].inverse() * poses[hi])));
}

std::vector<std::pair<int, double>> camera_images(const NetworkSource& source, size_t i) {
  const int n = source.camera_frame_count(i);
  bool listed = false;
  for (int k = 0; k < n && !listed; ++k) listed = source.listed_time(i, k).has_value();
  std::vector<std::pair<int, double>> out;
  for (int k = 0; k < n; ++k) {
    if (listed) {
      if (const auto t = source.listed_time(i, k)) out.emplace_back(k, *t);
    } else {
      out.emplace_back(k, source.frame_time(i, k));
    }
  }
  return out;
}

std::optional<std::string> clock_mismatch(const NetworkSource& source) {
  const io::NetworkConfig& net = source.network();
  for (size_t i = 0; i < net.cameras.size(); ++i)
    if (net.camera_fps(i) != net.fps)
      return "camera " + std::to_string(net.cameras[i].id) + " runs at " + fmt(net.camera_fps(i)) +
             " frames/s, the dataset at " + fmt(net.fps) + " (" + net.source + ")";
  // Times of the same frame index, where both cameras have one: from timestamps.csv, or
  // frame / fps for a camera it does not list at all (a listed camera without a row there has
  // no image there).
  const int frames = source.frame_count();
  std::vector<bool> listed(net.cameras.size(), false);
  for (size_t i = 0; i < net.cameras.size(); ++i)
    for (int k = 0; k < frames && !listed[i]; ++k) listed[i] = source.listed_time(i, k).has_value();
  const auto time = [&](size_t i, int k) -> std::optional<double> {
    if (listed[i]) return source.listed_time(i, k);
    return source.frame_time(i, k);
  };
  for (int k = 0; k < frames; ++k) {
    std::optional<size_t> ref;  // the first camera with a time at frame k
    for (size_t i = 0; i < net.cameras.size(); ++i) {
      const auto b = time(i, k);
      if (!b) continue;
      if (!ref) {
        ref = i;
        continue;
      }
      const double a = *time(*ref, k);
      if (std::abs(a - *b) > 1e-9)
        return "frame " + std::to_string(k) + " is at t = " + fmt(a) + " s for camera " +
               std::to_string(net.cameras[*ref].id) + " but " + fmt(*b) + " s for camera " +
               std::to_string(net.cameras[i].id) + " (timestamps.csv)";
    }
  }
  return std::nullopt;
}

std::optional<std::string> irregular_clock(const NetworkSource& source) {
  const io::NetworkConfig& net = source.network();
  std::optional<double> t0;
  for (size_t i = 0; i < net.cameras.size(); ++i)
    for (const auto& [k, t] : camera_images(source, i)) {
      if (!t0) t0 = t - k / net.fps;
      if (std::abs(t - *t0 - k / net.fps) > 1e-6)
        return "camera " + std::to_string(net.cameras[i].id) + "'s frame " + std::to_string(k) +
               " is at t = " + fmt(t) + " s, not " + fmt(*t0 + k / net.fps) + " s (frame / " +
               fmt(net.fps) + " frames/s from the first image)";
    }
  return std::nullopt;
}

void require_static_cameras(const NetworkSource& source, const std::string& what) {
  if (source.cameras_move())
    throw InputError(source.name() + ": cameras.csv: the camera poses change over time (or " +
                     "differ from network.yaml's), and " + what +
                     " handles static cameras at their network.yaml poses only (use netvmo run)");
}

void require_single_target(const World& world, const std::string& what) {
  const auto& targets = world.network().targets;
  if (targets.size() > 1)
    throw InputError(world.network().source + ": targets: " + std::to_string(targets.size()) +
                     " targets, and " + what + " runs one target's observer only (use netvmo run)");
}

std::unique_ptr<NetworkSource> open_dataset_source(const fs::path& dir,
                                                   std::optional<int> only_camera, bool keep_going,
                                                   const fs::path& shown_as) {
  return std::make_unique<DatasetSource>(dir, only_camera, keep_going, shown_as);
}

}  // namespace netvmo::sources
