#include "netvmo/pipeline/io/dataset_writer.hpp"

#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/progress.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {
std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}
}  // namespace

void write_calibration(const fs::path& file, const render::Intrinsics& k) {
  cv::FileStorage fsw(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fsw << "image_width" << k.width;
  fsw << "image_height" << k.height;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  fsw << "camera_matrix" << K;
  cv::Mat d(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) d.at<double>(0, i) = k.dist[size_t(i)];
  fsw << "distortion_coefficients" << d;
  io::write_file_atomic(file, fsw.releaseAndGetString());
}

std::string network_yaml(const render::SceneDescription& scene, int frames) {
  YAML::Emitter y;
  y.SetDoublePrecision(12);
  y << YAML::BeginMap;
  y << YAML::Key << "fps" << YAML::Value << scene.fps;
  y << YAML::Key << "frames" << YAML::Value << frames;
  y << YAML::Key << "target" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "family" << YAML::Value << scene.target.tag.family;
  y << YAML::Key << "id" << YAML::Value << scene.target.tag.id;
  y << YAML::Key << "size" << YAML::Value << scene.target.tag.size;
  y << YAML::EndMap;
  y << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : scene.cameras) {
    const render::Vec3 p = c.g_wi_believed.translation();
    const render::Vec3 r = obs::log_so3(c.g_wi_believed.linear());
    y << YAML::BeginMap;
    y << YAML::Key << "id" << YAML::Value << c.id;
    y << YAML::Key << "p_wi" << YAML::Value << YAML::Flow
      << std::vector<double>{p.x(), p.y(), p.z()};
    y << YAML::Key << "r_wi" << YAML::Value << YAML::Flow
      << std::vector<double>{r.x(), r.y(), r.z()};
    y << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "edges" << YAML::Value << YAML::BeginSeq;
  for (const auto& e : scene.edges) y << YAML::Flow << std::vector<int>{e.first, e.second};
  y << YAML::EndSeq;
  y << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

std::string truth_csv_header() {
  return "frame,t,camera,in_fov,visible_fraction,u0,v0,u1,v1,u2,v2,u3,v3";
}

std::string truth_csv_row(const render::FrameTruth& t) {
  std::string row = std::to_string(t.frame) + "," + fmt("%.6f", t.t) + "," +
                    std::to_string(t.camera_id) + "," + (t.in_fov ? "1" : "0") + "," +
                    fmt("%.6f", t.visible_fraction);
  for (const auto& c : t.corners) {
    if (c)
      row += "," + fmt("%.4f", c->x()) + "," + fmt("%.4f", c->y());
    else
      row += ",,";
  }
  return row;
}

DatasetSummary write_dataset(render::Renderer& r, const fs::path& out, const DatasetOptions& opt) {
  const render::SceneDescription& scene = r.scene();
  const int frames = opt.frames > 0 ? opt.frames : scene.frames;
  io::ensure_directory(out);
  io::ensure_directory(out / "calib");
  for (const auto& c : scene.cameras) {
    io::ensure_directory(out / ("cam_" + std::to_string(c.id)));
    write_calibration(out / "calib" / ("cam_" + std::to_string(c.id) + ".yaml"), c.intrinsics);
  }
  io::write_file_atomic(out / "network.yaml", network_yaml(scene, frames));
  {
    // The true (rendering) camera poses, for evaluation: g_io,true = g_wi,true^-1 g_wo.
    io::AtomicFile cams(out / "truth_cameras.csv");
    cams << "camera,px,py,pz,rx,ry,rz\n";
    for (const auto& c : scene.cameras) {
      const render::Vec3 p = c.g_wi_true.translation(), rv = obs::log_so3(c.g_wi_true.linear());
      cams << c.id;
      for (int i = 0; i < 3; ++i) cams << "," << fmt("%.9g", p[i]);
      for (int i = 0; i < 3; ++i) cams << "," << fmt("%.9g", rv[i]);
      cams << "\n";
    }
    cams.commit();
  }

  DatasetSummary summary;
  summary.frames = frames;
  for (const auto& c : scene.cameras) summary.cameras.push_back({c.id, 0, 0});

  io::AtomicFile truth(out / "truth.csv");
  io::AtomicFile target(out / "target.csv");
  truth << truth_csv_header() << "\n";
  target << "frame,t,px,py,pz,rx,ry,rz\n";
  Progress progress("render", frames, opt.progress);
  std::vector<uchar> png;
  for (int f = 0; f < frames; ++f) {
    r.set_frame(f);
    const render::Pose g_wo = r.target_pose(f);
    const render::Vec3 p = g_wo.translation(), rv = obs::log_so3(g_wo.linear());
    target << f << "," << fmt("%.6f", r.time_of(f));
    for (int i = 0; i < 3; ++i) target << "," << fmt("%.9g", p[i]);
    for (int i = 0; i < 3; ++i) target << "," << fmt("%.9g", rv[i]);
    target << "\n";
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
      truth << truth_csv_row(t) << "\n";
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
