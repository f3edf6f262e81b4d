#include "netvmo/pipeline/io/dataset_writer.hpp"

#include <cstdio>
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

DatasetSummary write_dataset(render::Renderer& r, const fs::path& out, const DatasetOptions& opt) {
  const render::SceneDescription& scene = r.scene();
  const int frames = opt.frames > 0 ? opt.frames : scene.frames;
  io::ensure_directory(out);
  io::ensure_directory(out / "calib");
  for (const auto& c : scene.cameras) {
    io::ensure_directory(out / ("cam_" + std::to_string(c.id)));
    save_calibration_opencv(out / "calib" / ("cam_" + std::to_string(c.id) + ".yaml"),
                            scene_calibration(c));
  }
  io::write_file_atomic(out / "network.yaml", network_yaml(scene_network_config(scene, frames)));
  {
    // Per camera image: the believed pose (cameras.csv, what the camera thinks it is) and the
    // true (rendering) pose, for evaluation: g_io,true = g_wi,true^-1 g_wo.
    io::AtomicFile believed(out / "cameras.csv"), truth(out / "truth_cameras.csv");
    believed << kCameraPosesHeader << "\n";
    truth << kCameraPosesHeader << "\n";
    for (int ci = 0; ci < r.camera_count(); ++ci)
      for (int f = 0; f < frames; ++f) {
        const int id = scene.cameras[size_t(ci)].id;
        believed << format_camera_pose_row(id, f, r.time_of(f), r.believed_camera_pose(ci, f))
                 << "\n";
        truth << format_camera_pose_row(id, f, r.time_of(f), r.camera_pose(ci, f)) << "\n";
      }
    believed.commit();
    truth.commit();
  }

  DatasetSummary summary;
  summary.frames = frames;
  for (const auto& c : scene.cameras) summary.cameras.push_back({c.id, 0, 0});

  io::AtomicFile truth(out / "truth.csv");
  io::AtomicFile target(out / "target.csv");
  truth << kTruthHeader << "\n";
  target << kTargetHeader << "\n";
  Progress progress("render", frames, opt.progress);
  std::vector<uchar> png;
  for (int f = 0; f < frames; ++f) {
    r.set_frame(f);
    target << format_target_row(f, r.time_of(f), r.target_pose(f)) << "\n";
    for (int ci = 0; ci < r.camera_count(); ++ci) {
      const int id = scene.cameras[size_t(ci)].id;
      const cv::Mat img = r.render(ci, f);
      if (!cv::imencode(".png", img, png))
        throw InputError("cannot encode PNG for camera " + std::to_string(id));
      char name[32];
      std::snprintf(name, sizeof name, "%06d.png", f);
      io::write_file_atomic(out / ("cam_" + std::to_string(id)) / name,
                            std::string(reinterpret_cast<const char*>(png.data()), png.size()));
      const render::FrameTruth t = r.truth(ci, f);
      truth << format_truth_row(t) << "\n";
      summary.cameras[size_t(ci)].frames_in_fov += t.in_fov ? 1 : 0;
      summary.cameras[size_t(ci)].frames_visible += t.visible_fraction > 0 ? 1 : 0;
    }
    progress.update(f + 1);
  }
  truth.commit();
  target.commit();
  progress.finish();
  // A dataset rewritten with fewer frames must not keep the old run's extra images.
  for (const auto& c : scene.cameras)
    for (const auto& e : fs::directory_iterator(out / ("cam_" + std::to_string(c.id)))) {
      const std::string name = e.path().filename().string();
      if (name.size() == 10 && name.compare(6, 4, ".png") == 0 &&
          name.find_first_not_of("0123456789") == 6 && std::stoi(name.substr(0, 6)) >= frames) {
        std::error_code ec;
        fs::remove(e.path(), ec);
      }
    }
  return summary;
}

}  // namespace netvmo::io
