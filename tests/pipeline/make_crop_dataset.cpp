// Test utility: turns a photo with known tag corners into a recorded dataset folder with ground
// truth, one "camera" per tag: each tag cropped with `--grow` x its size of context on every side
// (neighbouring faces of a cube, other tags), so that `netvmo detect` reports recall against tag
// size on real images. The corner file is libapriltag's test format (its test/data/*.txt): one
// line per tag, "id, (x0 y0), (x1 y1), (x2 y2), (x3 y3)", libapriltag pixel coordinates (pixel
// centres at +0.5), corners in libapriltag's order. The crops share one target id (`--id`);
// tags of other ids are skipped. The calibration is a nominal pinhole (no distortion: the
// photos' own is unknown), so PnP on these folders means nothing; detection does not use it.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

int main(int argc, char** argv) {
  CLI::App app{"Crop every tag of a photo into a recorded dataset folder (test utility)"};
  std::string image_path, corners_path, out;
  double grow = 1.0;
  int id = 0;
  app.add_option("image", image_path, "Photo (any format OpenCV reads)")->required();
  app.add_option("corners", corners_path, "Corner file (libapriltag test/data format)")->required();
  app.add_option("out", out, "Output dataset folder")->required();
  app.add_option("--grow", grow, "Context around each tag, in tag sizes")->capture_default_str();
  app.add_option("--id", id, "Target id (tags of other ids are skipped)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const cv::Mat image = cv::imread(image_path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "error: %s: cannot read the image\n", image_path.c_str());
    return 1;
  }
  std::ifstream in(corners_path);
  if (!in) {
    std::fprintf(stderr, "error: %s: cannot open\n", corners_path.c_str());
    return 1;
  }
  io::NetworkConfig net;
  net.fps = 1.0;
  net.frames = 1;
  net.target().id = id;
  net.target().size = 0.05;
  io::ensure_directory(fs::path(out) / "calib");
  std::string truth = std::string(io::kTruthHeader) + "\n";
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    for (char& ch : line)
      if (ch == ',' || ch == '(' || ch == ')') ch = ' ';
    std::istringstream ls(line);
    int tag_id = -1;
    std::array<cv::Point2d, 4> c;
    ls >> tag_id;
    for (auto& p : c) ls >> p.x >> p.y;
    if (!ls) {
      std::fprintf(stderr, "error: %s:%d: expected 'id, (x y), (x y), (x y), (x y)'\n",
                   corners_path.c_str(), lineno);
      return 1;
    }
    if (tag_id != id) continue;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (auto& p : c) {
      p -= cv::Point2d(0.5, 0.5);  // libapriltag pixel centres at +0.5 -> OpenCV
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y),
      y1 = std::max(y1, p.y);
    }
    const double g = grow * std::max(x1 - x0, y1 - y0);
    const cv::Rect crop = cv::Rect(cv::Point(cvFloor(x0 - g), cvFloor(y0 - g)),
                                   cv::Point(cvCeil(x1 + g) + 1, cvCeil(y1 + g) + 1)) &
                          cv::Rect(0, 0, image.cols, image.rows);
    const int cam = static_cast<int>(net.cameras.size()) + 1;
    net.cameras.push_back({cam, obs::SE3::Identity(), std::nullopt, {}, {}});
    io::Calibration calib;
    calib.width = crop.width;
    calib.height = crop.height;
    calib.K = cv::Matx33d(500, 0, (crop.width - 1) / 2.0, 0, 500, (crop.height - 1) / 2.0, 0, 0, 1);
    io::save_calibration_opencv(fs::path(out) / "calib" / ("cam_" + std::to_string(cam) + ".yaml"),
                                calib);
    const fs::path dir = fs::path(out) / ("cam_" + std::to_string(cam));
    io::ensure_directory(dir);
    if (!cv::imwrite((dir / "000000.png").string(), image(crop))) {
      std::fprintf(stderr, "error: %s: cannot write\n", (dir / "000000.png").c_str());
      return 1;
    }
    render::FrameTruth t;
    t.camera_id = cam;
    t.in_fov = true;
    t.visible_fraction = 1.0;
    for (size_t k = 0; k < 4; ++k) t.corners[k] = Eigen::Vector2d(c[k].x - crop.x, c[k].y - crop.y);
    truth += io::format_truth_row(t) + "\n";
  }
  for (size_t i = 1; i < net.cameras.size(); ++i)
    net.edges.emplace_back(net.cameras[i - 1].id, net.cameras[i].id);
  io::write_file_atomic(fs::path(out) / "network.yaml", io::network_yaml(net));
  io::write_file_atomic(fs::path(out) / "truth.csv", truth);
  std::printf("wrote %s: %zu tags of id %d\n", out.c_str(), net.cameras.size(), id);
  return 0;
}
