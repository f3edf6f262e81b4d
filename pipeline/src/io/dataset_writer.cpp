#include "netvmo/pipeline/io/dataset_writer.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/progress.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {

// Every camera's image times (render::SceneDescription::image_times) and the render frames that
// cover them: the sorted union of all cameras' times (times within 1e-9 s are one frame), and
// per camera the render frame of each of its images. On the scene's clock the union is
// k / fps and every camera has an image at every frame.
struct RenderClock {
  std::vector<double> frames;               ///< render frame -> time [s]
  std::vector<std::vector<double>> times;   ///< [camera][its frame] -> time [s]
  std::vector<std::vector<int>> own_frame;  ///< [camera][render frame] -> its frame, or -1
};

RenderClock render_clock(const render::SceneDescription& scene, int frames) {
  RenderClock c;
  for (size_t ci = 0; ci < scene.cameras.size(); ++ci) {
    c.times.push_back(scene.image_times(ci, frames));
    c.frames.insert(c.frames.end(), c.times.back().begin(), c.times.back().end());
  }
  std::sort(c.frames.begin(), c.frames.end());
  c.frames.erase(std::unique(c.frames.begin(), c.frames.end(),
                             [](double a, double b) { return b - a <= 1e-9; }),
                 c.frames.end());
  for (const auto& t : c.times) {
    c.own_frame.emplace_back(c.frames.size(), -1);
    size_t u = 0;
    for (size_t k = 0; k < t.size(); ++k) {
      while (c.frames[u] < t[k] - 1e-9) ++u;
      c.own_frame.back()[u] = static_cast<int>(k);
    }
  }
  return c;
}

// Per camera image: its time (timestamps.csv), the believed pose (cameras.csv, what the camera
// thinks it is) and the true (rendering) pose, for evaluation: g_io,true = g_wi,true^-1 g_wo.
void write_camera_files(const render::Renderer& r, const RenderClock& clock, const fs::path& out) {
  const render::SceneDescription& scene = r.scene();
  io::AtomicFile stamps(out / "timestamps.csv"), believed(out / "cameras.csv"),
      truth(out / "truth_cameras.csv");
  stamps << kTimestampsHeader << "\n";
  believed << kCameraPosesHeader << "\n";
  truth << kCameraPosesHeader << "\n";
  for (int ci = 0; ci < r.camera_count(); ++ci) {
    const auto& times = clock.times[size_t(ci)];
    const auto& own = clock.own_frame[size_t(ci)];
    for (int f = 0; f < static_cast<int>(times.size()); ++f) {
      const int id = scene.cameras[size_t(ci)].id;
      const int u = static_cast<int>(std::find(own.begin(), own.end(), f) - own.begin());
      stamps << format_timestamp_row(id, f, times[size_t(f)]) << "\n";
      believed << format_camera_pose_row(id, f, r.time_of(u), r.believed_camera_pose(ci, u))
               << "\n";
      truth << format_camera_pose_row(id, f, r.time_of(u), r.camera_pose(ci, u)) << "\n";
    }
  }
  stamps.commit();
  believed.commit();
  truth.commit();
}

// Camera `camera`'s image `frame` as cam_<id>/<frame>.png, or .jpg at the camera's
// sensor.jpeg_quality (OpenCV's encoder); `buffer` holds the encoded bytes.
void write_image(const render::CameraSpec& camera, int frame, const cv::Mat& img,
                 const fs::path& out, std::vector<uchar>& buffer) {
  const int quality = camera.sensor.jpeg_quality;
  const char* ext = quality > 0 ? ".jpg" : ".png";
  const std::vector<int> params =
      quality > 0 ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, quality} : std::vector<int>{};
  if (!cv::imencode(ext, img, buffer, params))
    throw InputError(std::string("cannot encode ") + ext + " for camera " +
                     std::to_string(camera.id));
  char name[32];
  std::snprintf(name, sizeof name, "%06d%s", frame, ext);
  io::write_file_atomic(out / ("cam_" + std::to_string(camera.id)) / name,
                        std::string(reinterpret_cast<const char*>(buffer.data()), buffer.size()));
}

// A dataset rewritten with fewer frames must not keep the old run's extra images: every
// cam_<id>/NNNNNN.png or .jpg from the camera's own image count on is removed.
void remove_stale_images(const render::SceneDescription& scene, const RenderClock& clock,
                         const fs::path& out) {
  for (size_t ci = 0; ci < scene.cameras.size(); ++ci) {
    const int own = static_cast<int>(clock.times[ci].size());
    for (const auto& e :
         fs::directory_iterator(out / ("cam_" + std::to_string(scene.cameras[ci].id)))) {
      const std::string name = e.path().filename().string();
      if (name.size() == 10 &&
          (name.compare(6, 4, ".png") == 0 || name.compare(6, 4, ".jpg") == 0) &&
          name.find_first_not_of("0123456789") == 6 && std::stoi(name.substr(0, 6)) >= own) {
        std::error_code ec;
        fs::remove(e.path(), ec);
      }
    }
  }
}

}  // namespace

DatasetSummary write_dataset(render::Renderer& r, const fs::path& out, const DatasetSettings& opt) {
  const render::SceneDescription& scene = r.scene();
  const int frames = opt.frames > 0 ? opt.frames : scene.frames;
  // Cameras on their own clocks (scenario `fps`, `start`): render frame u is at the u-th time
  // of the union of every camera's image times, and each camera renders only its own.
  const RenderClock clock = render_clock(scene, frames);
  if (!scene.one_clock()) r.set_frame_times(clock.frames);
  io::ensure_directory(out);
  io::ensure_directory(out / "calib");
  for (const auto& c : scene.cameras) {
    io::ensure_directory(out / ("cam_" + std::to_string(c.id)));
    save_calibration_opencv(out / "calib" / ("cam_" + std::to_string(c.id) + ".yaml"),
                            scene_calibration(c));
  }
  const NetworkConfig net = scene_network_config(scene, frames);
  io::write_file_atomic(out / "network.yaml", network_yaml(net));
  write_camera_files(r, clock, out);

  DatasetSummary summary;
  summary.frames = frames;
  for (size_t ci = 0; ci < scene.cameras.size(); ++ci)
    summary.cameras.push_back(
        {scene.cameras[ci].id, 0, 0, static_cast<int>(clock.times[ci].size())});

  // truth.csv: a row per camera image (its own frame and time); target.csv: a row per render
  // frame, i.e. at every image time of any camera (frame = the index of that time).
  // Several targets: target_<id>.csv for each after the first (truth.csv's corners are the
  // first target's).
  io::AtomicFile truth(out / "truth.csv");
  std::vector<std::unique_ptr<io::AtomicFile>> targets;
  for (size_t j = 0; j < scene.targets.size(); ++j) {
    targets.push_back(std::make_unique<io::AtomicFile>(out / target_truth_file(net, j)));
    *targets.back() << kTargetHeader << "\n";
  }
  truth << kTruthHeader << "\n";
  const int render_frames = static_cast<int>(clock.frames.size());
  Progress progress("render", render_frames, opt.progress);
  std::vector<uchar> encoded;
  for (int u = 0; u < render_frames; ++u) {
    r.set_frame(u);
    for (size_t j = 0; j < targets.size(); ++j)
      *targets[j] << format_target_row(u, r.time_of(u), r.target_pose(u, j)) << "\n";
    for (int ci = 0; ci < r.camera_count(); ++ci) {
      const int f = clock.own_frame[size_t(ci)][size_t(u)];
      if (f < 0) continue;  // this camera takes no image at this time
      write_image(scene.cameras[size_t(ci)], f, r.render(ci, u), out, encoded);
      render::FrameTruth t = r.truth(ci, u);
      t.frame = f;
      truth << format_truth_row(t) << "\n";
      summary.cameras[size_t(ci)].frames_in_fov += t.in_fov ? 1 : 0;
      summary.cameras[size_t(ci)].frames_visible += t.visible_fraction > 0 ? 1 : 0;
    }
    progress.update(u + 1);
  }
  truth.commit();
  for (auto& t : targets) t->commit();
  progress.finish();
  remove_stale_images(scene, clock, out);
  return summary;
}

}  // namespace netvmo::io
