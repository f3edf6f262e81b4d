#include "netvmo/pipeline/frame_source.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <set>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::pipeline {
namespace fs = std::filesystem;

namespace {

constexpr long kMaxFrameNumber = 100'000'000;

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_image_ext(const fs::path& p) {
  const std::string e = lower(p.extension().string());
  return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".pgm";
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(),
                                   [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

cv::Mat to_gray(const cv::Mat& m) {
  if (m.empty() || m.type() == CV_8UC1) return m;
  cv::Mat g;
  if (m.channels() == 3) cv::cvtColor(m, g, cv::COLOR_BGR2GRAY);
  else if (m.channels() == 4) cv::cvtColor(m, g, cv::COLOR_BGRA2GRAY);
  else g = m;
  if (g.depth() != CV_8U) g.convertTo(g, CV_8U, g.depth() == CV_16U ? 1.0 / 257.0 : 1.0);
  return g;
}

class ImageFolderSource : public FrameSource {
 public:
  explicit ImageFolderSource(fs::path dir) : dir_(std::move(dir)) {
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir_, ec))
      if (e.is_regular_file() && is_image_ext(e.path())) files.push_back(e.path());
    if (ec) throw InputError(dir_.string() + "/: cannot list folder: " + ec.message());
    if (files.empty())
      throw InputError(dir_.string() + "/: no images (png, jpg, jpeg, pgm) in the folder");
    std::sort(files.begin(), files.end(),
              [](const fs::path& a, const fs::path& b) { return a.filename() < b.filename(); });
    const bool numeric = std::all_of(files.begin(), files.end(), [](const fs::path& p) {
      return all_digits(p.stem().string());
    });
    if (!numeric) {
      frames_ = files;
      return;
    }
    std::map<long, fs::path> by_number;
    for (const auto& p : files) {
      const std::string stem = p.stem().string();
      if (stem.size() > 9 || std::stol(stem) > kMaxFrameNumber)
        throw InputError(p.string() + ": frame number too large");
      const long n = std::stol(stem);
      auto [it, inserted] = by_number.emplace(n, p);
      if (!inserted)
        throw InputError(p.string() + ": same frame number as " + it->second.filename().string() +
                         "; keep one of them");
    }
    frames_.resize(static_cast<size_t>(by_number.rbegin()->first + 1));
    for (const auto& [n, p] : by_number) frames_[static_cast<size_t>(n)] = p;
    for (size_t i = 0; i < frames_.size(); ++i)
      if (frames_[i].empty()) missing_.push_back(static_cast<int>(i));
  }
  int frame_count() const override { return static_cast<int>(frames_.size()); }
  bool has_frame(int f) const override {
    return f >= 0 && f < frame_count() && !frames_[static_cast<size_t>(f)].empty();
  }
  cv::Mat read(int f) override {
    if (!has_frame(f)) return {};
    const fs::path& p = frames_[static_cast<size_t>(f)];
    cv::Mat m;
    try {
      m = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
      throw InputError(p.string() + ": cannot read image: " + e.err);
    }
    if (m.empty())
      throw InputError(p.string() + ": cannot read image (unreadable, corrupt or not an image)");
    return to_gray(m);
  }
  std::string frame_name(int f) const override {
    if (has_frame(f)) return frames_[static_cast<size_t>(f)].string();
    return dir_.string() + "/ frame " + std::to_string(f) + " (missing)";
  }
  const fs::path& path() const override { return dir_; }
  std::vector<int> missing_frames() const override { return missing_; }

 private:
  fs::path dir_;
  std::vector<fs::path> frames_;  // by frame index; empty path = missing
  std::vector<int> missing_;
};

class VideoSource : public FrameSource {
 public:
  explicit VideoSource(fs::path file) : file_(std::move(file)) {
    open();
    const double n = cap_.get(cv::CAP_PROP_FRAME_COUNT);
    if (std::isfinite(n) && n > 0) {
      count_ = static_cast<int>(std::lround(n));
    } else {  // container does not say: count by decoding
      count_ = 0;
      while (cap_.grab()) ++count_;
      open();
    }
  }
  int frame_count() const override { return count_; }
  bool has_frame(int f) const override { return f >= 0 && f < count_; }
  cv::Mat read(int f) override {
    if (!has_frame(f)) return {};
    if (f < next_) open();
    while (next_ < f) {
      if (!cap_.grab()) fail(next_);
      ++next_;
    }
    cv::Mat m;
    if (!cap_.read(m) || m.empty()) fail(f);
    ++next_;
    return to_gray(m).clone();
  }
  std::string frame_name(int f) const override {
    return file_.string() + " frame " + std::to_string(f);
  }
  const fs::path& path() const override { return file_; }

 private:
  void open() {
    cap_.release();
    bool ok = false;
    try {
      ok = cap_.open(file_.string(), cv::CAP_ANY);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || !cap_.isOpened())
      throw InputError(file_.string() + ": cannot open video (unsupported or corrupt file)");
    next_ = 0;
  }
  [[noreturn]] void fail(int f) {
    const int at = f;
    open();  // leave the capture in a known state for the next call
    throw InputError(file_.string() + ": cannot decode frame " + std::to_string(at) + " of " +
                     std::to_string(count_) + " (corrupt or truncated video)");
  }
  fs::path file_;
  cv::VideoCapture cap_;
  int count_ = 0;
  int next_ = 0;
};

bool looks_like_opencv_storage(const fs::path& xml) {
  std::ifstream in(xml);
  std::string head(512, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  return head.find("<opencv_storage>") != std::string::npos;
}

std::string list_frames(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size() && i < 5; ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  if (v.size() > 5) s += ", ...";
  return s;
}

}  // namespace

std::unique_ptr<FrameSource> open_image_folder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + "/: image folder not found");
  return std::make_unique<ImageFolderSource>(dir);
}

std::unique_ptr<FrameSource> open_video(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw InputError(file.string() + ": video file not found");
  return std::make_unique<VideoSource>(file);
}

cv::Mat Dataset::read(size_t camera_index, int frame) {
  DatasetCamera& cam = cameras.at(camera_index);
  if (!cam.source)
    throw InputError(dir.string() + ": camera " + std::to_string(cam.id) + " was not opened");
  if (frame >= frame_count) return {};
  cv::Mat m = cam.source->read(frame);
  if (!m.empty() && (m.cols != cam.calib.width || m.rows != cam.calib.height))
    throw InputError(cam.source->frame_name(frame) + ": image is " + std::to_string(m.cols) + "x" +
                     std::to_string(m.rows) + " but " + cam.calib.source + " says " +
                     std::to_string(cam.calib.width) + "x" + std::to_string(cam.calib.height));
  return m;
}

Dataset open_dataset(const fs::path& dir, std::optional<int> only_camera) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": dataset folder not found");
  Dataset ds;
  ds.dir = dir;
  ds.network = load_network_config(dir / "network.yaml");

  std::set<std::string> declared;
  for (const auto& cc : ds.network.cameras) {
    const std::string name = "cam_" + std::to_string(cc.id);
    declared.insert(name);
    DatasetCamera cam;
    cam.id = cc.id;
    if (only_camera && cc.id != *only_camera) {
      ds.cameras.push_back(std::move(cam));
      continue;
    }
    // Calibration
    const fs::path cdir = dir / "calib";
    const fs::path yaml = cdir / (name + ".yaml"), yml = cdir / (name + ".yml"),
                   xml = cdir / (name + ".xml");
    if (fs::exists(yaml)) {
      cam.calib = load_calibration_opencv(yaml);
    } else if (fs::exists(yml)) {
      cam.calib = load_calibration_opencv(yml);
    } else if (fs::exists(xml)) {
      cam.calib = looks_like_opencv_storage(xml) ? load_calibration_opencv(xml)
                                                 : load_calibration_visp_xml(xml, name);
    } else {
      throw InputError(yaml.string() + ": calibration not found for camera " +
                       std::to_string(cc.id) + " (also looked for " + name + ".yml and " + name +
                       ".xml)");
    }
    // Frames: an image folder or a video file
    const fs::path folder = dir / name;
    std::vector<fs::path> videos;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().stem() == name) videos.push_back(e.path());
    std::sort(videos.begin(), videos.end());
    const bool has_folder = fs::is_directory(folder);
    if (has_folder && !videos.empty())
      throw InputError(videos[0].string() + ": camera " + std::to_string(cc.id) +
                       " has both an image folder " + name + "/ and a video; keep one");
    if (videos.size() > 1)
      throw InputError(videos[1].string() + ": camera " + std::to_string(cc.id) +
                       " has several videos (" + videos[0].filename().string() + ", " +
                       videos[1].filename().string() + "); keep one");
    if (has_folder) cam.source = open_image_folder(folder);
    else if (!videos.empty()) cam.source = open_video(videos[0]);
    else
      throw InputError(folder.string() + "/: no image folder or video file " + name +
                       ".<ext> for camera " + std::to_string(cc.id) + " of network.yaml");
    const auto missing = cam.source->missing_frames();
    if (!missing.empty())
      ds.warnings.push_back(cam.source->path().string() + ": " + std::to_string(missing.size()) +
                            " missing frame(s) (" + list_frames(missing) + "); camera " +
                            std::to_string(cc.id) + " is blind there");
    ds.cameras.push_back(std::move(cam));
  }
  // Entries for cameras network.yaml does not declare are ignored, with a warning.
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string stem = e.path().stem().string();
    if (!only_camera && stem.rfind("cam_", 0) == 0 && all_digits(stem.substr(4)) &&
        !declared.count(stem))
      ds.warnings.push_back(e.path().string() + ": camera " + stem.substr(4) +
                            " is not in network.yaml; ignored");
  }
  // Frame count rule.
  int longest = 0;
  for (const auto& c : ds.cameras)
    if (c.source) longest = std::max(longest, c.source->frame_count());
  ds.frame_count = ds.network.frames ? *ds.network.frames : longest;
  for (const auto& c : ds.cameras) {
    if (!c.source) continue;
    const int n = c.source->frame_count();
    if (n < ds.frame_count)
      ds.warnings.push_back(c.source->path().string() + ": camera " + std::to_string(c.id) +
                            " has " + std::to_string(n) + " frames, the dataset " +
                            std::to_string(ds.frame_count) + "; it is blind from frame " +
                            std::to_string(n) + " on");
    else if (n > ds.frame_count)
      ds.warnings.push_back(c.source->path().string() + ": camera " + std::to_string(c.id) +
                            " has " + std::to_string(n) + " frames but network.yaml says frames: " +
                            std::to_string(ds.frame_count) + "; the extra frames are ignored");
  }
  return ds;
}

}  // namespace netvmo::pipeline
