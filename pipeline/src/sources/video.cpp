// Video files: cam_<id>.<ext>, anything cv::VideoCapture decodes (avi, mp4, mkv, ...).
#include <cmath>
#include <cstdio>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/sources/camera_stream.hpp"
#include "stream_util.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;
using detail::to_gray;

namespace {

class VideoStream : public CameraStream {
 public:
  explicit VideoStream(fs::path file) : file_(std::move(file)) {
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
    if (!has_frame(f) || (failed_at_ >= 0 && f > failed_at_)) return {};
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
  // CAP_PROP_POS_MSEC after grabbing frame k is that frame's presentation time (FFmpeg: its
  // pts); the times must increase strictly over the whole stream.
  std::vector<double> own_times(std::string& why_not) override {
    std::vector<double> t;
    open();
    for (int k = 0; k < count_; ++k) {
      if (!cap_.grab()) {
        why_not = "its frame " + std::to_string(k) + " cannot be decoded";
        t.clear();
        break;
      }
      t.push_back(cap_.get(cv::CAP_PROP_POS_MSEC) / 1000.0);
      if (!std::isfinite(t.back()) || (k > 0 && !(t.back() > t[t.size() - 2]))) {
        char b[160];
        std::snprintf(b, sizeof b,
                      "its timestamps do not increase (frame %d at %.6g s after %.6g s)", k,
                      t.back(), k > 0 ? t[t.size() - 2] : 0.0);
        why_not = b;
        t.clear();
        break;
      }
    }
    open();  // read() starts from the beginning again
    return t;
  }

 private:
  void open() {
    cap_.release();
    bool ok = false;
    // FFmpeg when OpenCV has it: the other backends (GStreamer) only add their own complaints
    // about a file FFmpeg cannot open.
    const int api =
        cv::videoio_registry::hasBackend(cv::CAP_FFMPEG) ? int(cv::CAP_FFMPEG) : int(cv::CAP_ANY);
    try {
      ok = cap_.open(file_.string(), api);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || !cap_.isOpened())
      throw InputError(file_.string() + ": cannot open video (unsupported or corrupt file)");
    next_ = 0;
  }
  // A stream that stops decoding does not come back: the camera is blind from that frame on
  // (later reads return no image instead of failing again).
  [[noreturn]] void fail(int f) {
    failed_at_ = f;
    next_ = count_;  // the next read of an earlier frame reopens
    throw InputError(file_.string() + ": cannot decode frame " + std::to_string(f) + " of " +
                     std::to_string(count_) +
                     " (corrupt or truncated video); blind from that frame on");
  }
  fs::path file_;
  cv::VideoCapture cap_;
  int count_ = 0;
  int next_ = 0;
  int failed_at_ = -1;  ///< the first frame that could not be decoded, or -1
};
}  // namespace

std::unique_ptr<CameraStream> open_video(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw InputError(file.string() + ": video file not found");
  return std::make_unique<VideoStream>(file);
}

namespace kinds {
namespace {
class Video final : public StreamKind {
 public:
  std::string_view name() const override { return "video"; }
  std::string_view description() const override {
    return "a video file cam_<id>.<ext> that OpenCV decodes (avi, mp4, mkv, ...)";
  }
  std::vector<fs::path> entries(const fs::path& dataset, const std::string& stem) const override {
    std::vector<fs::path> found;
    for (const auto& e : fs::directory_iterator(dataset))
      if (e.is_regular_file() && e.path().stem() == stem) found.push_back(e.path());
    std::sort(found.begin(), found.end());
    return found;
  }
  std::unique_ptr<CameraStream> open(const fs::path& entry) const override {
    return open_video(entry);
  }
};
}  // namespace

const StreamKind& video() {
  static const Video kind;
  return kind;
}
}  // namespace kinds

}  // namespace netvmo::sources
