// Image folders: cam_<id>/ holding images (io::is_image_file); the frame-count rule is in
// sources/dataset.hpp.
#include <algorithm>
#include <map>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "netvmo/pipeline/sources/camera_stream.hpp"
#include "stream_util.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;
using detail::all_digits;
using detail::to_gray;

namespace {

constexpr long kMaxFrameNumber = 100'000'000;

class ImageFolderStream : public CameraStream {
 public:
  explicit ImageFolderStream(fs::path dir) : dir_(std::move(dir)) {
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir_, ec))
      if (e.is_regular_file() && io::is_image_file(e.path())) files.push_back(e.path());
    if (ec) throw InputError(dir_.string() + "/: cannot list folder: " + ec.message());
    if (files.empty())
      throw InputError(dir_.string() + "/: no images (" + io::kImageExtensions + ") in the folder");
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
    return to_gray(io::read_gray_image(frames_[static_cast<size_t>(f)]));
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

}  // namespace

std::unique_ptr<CameraStream> open_image_folder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + "/: image folder not found");
  return std::make_unique<ImageFolderStream>(dir);
}

namespace kinds {
namespace {
class ImageFolder final : public StreamKind {
 public:
  std::string_view name() const override { return "image-folder"; }
  std::string_view description() const override {
    return "a folder cam_<id>/ of png, jpg, jpeg or pgm images";
  }
  std::vector<fs::path> entries(const fs::path& dataset, const std::string& stem) const override {
    std::vector<fs::path> found;
    if (fs::is_directory(dataset / stem)) found.push_back(dataset / stem);
    return found;
  }
  std::unique_ptr<CameraStream> open(const fs::path& entry) const override {
    return open_image_folder(entry);
  }
};
}  // namespace

const StreamKind& image_folder() {
  static const ImageFolder kind;
  return kind;
}
}  // namespace kinds

}  // namespace netvmo::sources
