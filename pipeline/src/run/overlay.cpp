#include "netvmo/pipeline/run/overlay.hpp"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;

namespace {
const cv::Scalar kText(255, 255, 255);

// The image averaged down to `size` (INTER_AREA's box filter). Where the reduction is an even
// whole factor it is first halved (2x2 means, OpenCV's fast path for an exact factor of 2) while
// it stays one: the same box filter to within a grey level of rounding, at less than half the
// cost of one resize for a mosaic tile of a 1280x720 image (docs/benchmarks.md,
// "Real-resolution recordings").
cv::Mat reduced(const cv::Mat& gray, cv::Size size) {
  cv::Mat img = gray;
  while (img.cols % (2 * size.width) == 0 && img.rows % (2 * size.height) == 0) {
    cv::Mat half;
    cv::resize(img, half, cv::Size(img.cols / 2, img.rows / 2), 0, 0, cv::INTER_AREA);
    img = half;
  }
  if (img.size() == size) return img;
  cv::Mat out;
  cv::resize(img, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

// A closed polygon with corner 0 circled, anti-aliased, at sub-pixel positions.
void polygon(cv::Mat& img, const std::vector<cv::Point2d>& pts, const cv::Scalar& color,
             int thickness, int radius) {
  constexpr int kShift = 4;  // sub-pixel drawing
  std::vector<cv::Point> p;
  for (const auto& q : pts)
    p.emplace_back(cvRound(q.x * (1 << kShift)), cvRound(q.y * (1 << kShift)));
  cv::polylines(img, p, true, color, thickness, cv::LINE_AA, kShift);
  cv::circle(img, p[0], radius << kShift, color, thickness, cv::LINE_AA, kShift);  // corner 0
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
                     const obs::SE3& g_wi, const std::vector<OverlayLayer>& layers, double scale) {
  const int width = gray.empty() ? calib.width : gray.cols;
  const int height = gray.empty() ? calib.height : gray.rows;
  const cv::Size size(std::max(1, cvRound(width * scale)), std::max(1, cvRound(height * scale)));
  cv::Mat img;
  if (gray.empty()) {
    img = cv::Mat(size, CV_8UC3, cv::Scalar(40, 40, 40));
  } else if (size == gray.size()) {
    cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  } else {
    cv::cvtColor(reduced(gray, size), img, cv::COLOR_GRAY2BGR);
  }
  // Pixel centres are at integers at either size.
  const double sx = static_cast<double>(size.width) / width,
               sy = static_cast<double>(size.height) / height;
  const auto scaled = [&](const std::vector<cv::Point2d>& pts) {
    std::vector<cv::Point2d> out;
    for (const auto& p : pts) out.emplace_back((p.x + 0.5) * sx - 0.5, (p.y + 0.5) * sy - 0.5);
    return out;
  };
  // Lines and text sized for the drawn image (as at 640 pixels across, never below legible).
  const double em = size.width / 640.0;
  const int thickness = em >= 0.75 ? 2 : 1;
  const int radius = std::max(2, cvRound(5 * em));
  const bool several = layers.size() > 1;
  std::string label = "cam " + std::to_string(camera_id);
  for (size_t j = 0; j < layers.size(); ++j) {
    const OverlayLayer& layer = layers[j];
    const auto [detected, estimate] = target_colors(j);
    if (layer.detected)
      polygon(img, scaled(std::vector<cv::Point2d>(layer.corners.begin(), layer.corners.end())),
              detected, thickness, radius);
    if (layer.estimate_w) {
      const obs::SE3 g_bar = g_wi.inverse() * *layer.estimate_w;  // the camera's own g_bar_i
      const auto model = obs::FeatureModel::square(layer.target->size);
      bool in_front = true;
      std::vector<cv::Point2d> xy;
      for (const auto& p : model.points_o) {
        const obs::Vec3 q = g_bar * p;
        in_front = in_front && q.z() > 1e-3;
        xy.emplace_back(q.x() / q.z(), q.y() / q.z());
      }
      if (in_front)
        polygon(img, scaled(io::denormalize_points(xy, calib)), estimate, thickness, radius);
    }
    if (j == 0 && layer.read_failed) label += "  unreadable";
    if (layer.read_failed) continue;
    if (several) label += "  " + std::to_string(layer.target->id) + ":";
    label += layer.detected ? (several ? " seen" : "  detected") : (several ? " -" : "  no target");
  }
  cv::putText(img, label, {cvRound(10 * em), cvRound(24 * em)}, cv::FONT_HERSHEY_SIMPLEX,
              std::max(0.35, 0.7 * em), kText, thickness, cv::LINE_AA);
  const std::string legend =
      several ? "light: detection  dark: networked estimate  (one colour pair per target)"
              : "green: detection  magenta: networked estimate";
  cv::putText(img, legend, {cvRound(10 * em), img.rows - cvRound(12 * em)},
              cv::FONT_HERSHEY_SIMPLEX, std::max(0.3, 0.45 * em), kText, 1, cv::LINE_AA);
  return img;
}

OverlayWriter::OverlayWriter(const fs::path& dir, const sources::World& world,
                             OverlaySettings settings)
    : dir_(dir / "overlays"), world_(world), settings_(settings) {
  if (settings_.tile_width < 16 || settings_.mosaic_columns < 1 || settings_.queue_frames < 1)
    throw std::invalid_argument(
        "OverlaySettings: tile_width >= 16, mosaic_columns >= 1 and "
        "queue_frames >= 1");
  io::ensure_directory(dir_);
  thread_ = std::thread([this] { work(); });
}

OverlayWriter::~OverlayWriter() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    closing_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::vector<OverlayLayer> overlay_layers(
    const io::NetworkConfig& net, size_t i,
    const std::vector<std::vector<frontend::Observation>>& cams,
    const std::vector<const run::FrameRecord*>& records) {
  std::vector<OverlayLayer> layers;
  for (size_t j = 0; j < records.size(); ++j) {
    const frontend::Observation& cam = cams[j][i];
    const CameraRecord& rec = records[j]->cameras[i];
    OverlayLayer layer;
    layer.detected = cam.delta;
    layer.corners = cam.corners_px;
    layer.read_failed = cam.read_failed;
    if (rec.initialized) layer.estimate_w = rec.est_w;
    layer.target = &net.targets[j];
    layers.push_back(layer);
  }
  return layers;
}

void OverlayWriter::rethrow_error() {
  std::lock_guard<std::mutex> lock(mu_);
  if (error_) std::rethrow_exception(error_);
}

void OverlayWriter::operator()(int /*frame*/, const std::vector<cv::Mat>& images,
                               const std::vector<std::vector<frontend::Observation>>& cams,
                               const std::vector<const run::FrameRecord*>& records) {
  const auto& net = world_.network();
  Job job;
  job.images = images;  // shared pixels: the run reads each frame into a new image
  job.layers.resize(net.cameras.size());
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    job.layers[i] = overlay_layers(net, i, cams, records);
    job.g_wi.push_back(world_.camera_believed(i, records[0]->frame));
  }
  std::unique_lock<std::mutex> lock(mu_);
  changed_.wait(
      lock, [&] { return error_ || queue_.size() < static_cast<size_t>(settings_.queue_frames); });
  if (error_) std::rethrow_exception(error_);
  queue_.push_back(std::move(job));
  changed_.notify_all();
}

void OverlayWriter::work() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mu_);
      changed_.wait(lock, [&] { return closing_ || !queue_.empty(); });
      if (queue_.empty()) return;  // closing, all done
      job = std::move(queue_.front());
      queue_.pop_front();
      changed_.notify_all();
      if (error_) continue;  // the first error stands; the rest is not drawn
    }
    try {
      draw(job);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu_);
      error_ = std::current_exception();
      changed_.notify_all();
    }
  }
}

void OverlayWriter::draw(const Job& job) {
  const auto& net = world_.network();
  const size_t n = net.cameras.size();
  const int cols = std::max(1, std::min<int>(settings_.mosaic_columns, static_cast<int>(n)));
  const int rows =
      static_cast<int>((n + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  cv::Size tile;
  for (size_t i = 0; i < n; ++i) {
    const auto& calib = world_.calibration(i);
    const auto& layers = job.layers[i];
    const int id = net.cameras[i].id;
    if (settings_.video && settings_.camera_videos) {
      const cv::Mat img = draw_overlay(job.images[i], id, calib, job.g_wi[i], layers);
      if (videos_.size() <= i) videos_.resize(n);
      if (!videos_[i].isOpened()) {
        const fs::path file = dir_ / ("cam_" + std::to_string(id) + ".mp4");
        videos_[i].open(file.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), net.fps,
                        img.size());
        if (!videos_[i].isOpened())
          throw InputError(file.string() + ": cannot open video for writing");
      }
      videos_[i].write(img);
    }
    const int width = job.images[i].empty() ? calib.width : job.images[i].cols;
    cv::Mat small = draw_overlay(job.images[i], id, calib, job.g_wi[i], layers,
                                 static_cast<double>(settings_.tile_width) / width);
    if (i == 0) {
      tile = small.size();
      last_mosaic_ = cv::Mat(tile.height * rows, tile.width * cols, CV_8UC3, cv::Scalar(0, 0, 0));
    }
    if (small.size() != tile) cv::resize(small, small, tile, 0, 0, cv::INTER_AREA);
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
  {
    std::lock_guard<std::mutex> lock(mu_);
    closing_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
  rethrow_error();
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
