#include "netvmo/pipeline/run/overlay.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;

namespace {
const cv::Scalar kText(255, 255, 255);

void polygon(cv::Mat& img, const std::vector<cv::Point2d>& pts, const cv::Scalar& color) {
  constexpr int kShift = 4;  // sub-pixel drawing
  std::vector<cv::Point> p;
  for (const auto& q : pts)
    p.emplace_back(cvRound(q.x * (1 << kShift)), cvRound(q.y * (1 << kShift)));
  cv::polylines(img, p, true, color, 2, cv::LINE_AA, kShift);
  cv::circle(img, p[0], 5 << kShift, color, 2, cv::LINE_AA, kShift);  // corner 0
}
}  // namespace

std::pair<cv::Scalar, cv::Scalar> target_colors(size_t j) {
  static const std::pair<cv::Scalar, cv::Scalar> kPairs[] = {
      {{60, 220, 60}, {220, 60, 220}},   // green, magenta
      {{230, 220, 40}, {40, 140, 255}},  // cyan, orange
      {{60, 220, 220}, {255, 90, 60}},   // yellow, blue
      {{200, 200, 200}, {60, 60, 230}},  // light grey, red
  };
  return kPairs[j % 4];
}

cv::Mat draw_overlay(const cv::Mat& gray, int camera_id, const io::Calibration& calib,
                     const obs::SE3& g_wi, const std::vector<OverlayLayer>& layers) {
  cv::Mat img;
  if (gray.empty())
    img = cv::Mat(calib.height, calib.width, CV_8UC3, cv::Scalar(40, 40, 40));
  else
    cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  const bool several = layers.size() > 1;
  std::string label = "cam " + std::to_string(camera_id);
  for (size_t j = 0; j < layers.size(); ++j) {
    const CameraFrame& cam = *layers[j].cam;
    const run::CameraRecord& rec = *layers[j].rec;
    const auto [detected, estimate] = target_colors(j);
    if (cam.obs.delta)
      polygon(img, std::vector<cv::Point2d>(cam.obs.corners_px.begin(), cam.obs.corners_px.end()),
              detected);
    if (rec.initialized) {
      const obs::SE3 g_bar = g_wi.inverse() * rec.est_w;  // the camera's own estimate g_bar_i
      const auto model = obs::FeatureModel::square(layers[j].target->size);
      bool in_front = true;
      std::vector<cv::Point2d> xy;
      for (const auto& p : model.points_o) {
        const obs::Vec3 q = g_bar * p;
        in_front = in_front && q.z() > 1e-3;
        xy.emplace_back(q.x() / q.z(), q.y() / q.z());
      }
      if (in_front) polygon(img, io::denormalize_points(xy, calib), estimate);
    }
    if (j == 0 && cam.read_failed) label += "  unreadable";
    if (cam.read_failed) continue;
    if (several) label += "  " + std::to_string(layers[j].target->id) + ":";
    label += cam.obs.delta ? (several ? " seen" : "  detected") : (several ? " -" : "  no target");
  }
  cv::putText(img, label, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, kText, 2, cv::LINE_AA);
  const std::string legend =
      several ? "light: detection  dark: networked estimate  (one colour pair per target)"
              : "green: detection  magenta: networked estimate";
  cv::putText(img, legend, {10, img.rows - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kText, 1,
              cv::LINE_AA);
  return img;
}

OverlayWriter::OverlayWriter(const fs::path& dir, const sources::NetworkSource& provider,
                             OverlaySettings settings)
    : dir_(dir / "overlays"), provider_(provider), settings_(settings) {
  io::ensure_directory(dir_);
}

void OverlayWriter::operator()(int /*frame*/, const std::vector<cv::Mat>& images,
                               const std::vector<std::vector<CameraFrame>>& cams,
                               const std::vector<const run::FrameRecord*>& records) {
  const auto& net = provider_.network();
  const size_t n = net.cameras.size();
  const int cols = std::max(1, std::min<int>(settings_.mosaic_columns, static_cast<int>(n)));
  const int rows =
      static_cast<int>((n + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  cv::Size tile;
  for (size_t i = 0; i < n; ++i) {
    const auto& calib = provider_.calibration(i);
    std::vector<OverlayLayer> layers;
    for (size_t j = 0; j < records.size(); ++j)
      layers.push_back({&cams[j][i], &records[j]->cameras[i], &net.targets[j]});
    const cv::Mat img = draw_overlay(images[i], net.cameras[i].id, calib,
                                     provider_.camera_believed(i, records[0]->frame), layers);
    if (settings_.video) {
      if (videos_.size() <= i) videos_.resize(n);
      if (!videos_[i].isOpened()) {
        const fs::path file = dir_ / ("cam_" + std::to_string(net.cameras[i].id) + ".mp4");
        videos_[i].open(file.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), net.fps,
                        img.size());
        if (!videos_[i].isOpened())
          throw InputError(file.string() + ": cannot open video for writing");
      }
      videos_[i].write(img);
    }
    cv::Mat small;
    cv::resize(img, small, cv::Size(), settings_.mosaic_scale, settings_.mosaic_scale,
               cv::INTER_AREA);
    if (i == 0) {
      tile = small.size();
      last_mosaic_ = cv::Mat(tile.height * rows, tile.width * cols, CV_8UC3, cv::Scalar(0, 0, 0));
    }
    if (small.size() != tile) cv::resize(small, small, tile);
    small.copyTo(last_mosaic_(cv::Rect(
        static_cast<int>(i % static_cast<size_t>(cols)) * tile.width,
        static_cast<int>(i / static_cast<size_t>(cols)) * tile.height, tile.width, tile.height)));
  }
  if (settings_.video) {
    if (!mosaic_video_.isOpened()) {
      const fs::path file = dir_ / "mosaic.mp4";
      mosaic_video_.open(file.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), net.fps,
                         last_mosaic_.size());
      if (!mosaic_video_.isOpened())
        throw InputError(file.string() + ": cannot open video for writing");
    }
    mosaic_video_.write(last_mosaic_);
  }
}

void OverlayWriter::finish() {
  for (auto& v : videos_) v.release();
  mosaic_video_.release();
  if (!last_mosaic_.empty()) {
    const fs::path png = dir_ / "mosaic.png", partial = dir_ / "mosaic.partial.png";
    if (!cv::imwrite(partial.string(), last_mosaic_))
      throw InputError(png.string() + ": cannot write");
    fs::rename(partial, png);
  }
}

}  // namespace netvmo::run
