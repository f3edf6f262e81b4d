// One camera's image stream (CameraStream) and the registry of stream kinds a dataset folder can
// hold for a camera: an image folder cam_<id>/ or a video file cam_<id>.<ext>. The network-level
// source of a run (every camera's stream, calibrations, ground truth) is NetworkSource
// (network_source.hpp); dataset folders are read by open_dataset() (dataset.hpp).
//
// Adding a stream kind: a file in pipeline/src/sources/ that implements CameraStream and defines a
// function returning its StreamKind, and one line in the table of
// pipeline/src/sources/stream_kinds.cpp.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "netvmo/observer/registry.hpp"

namespace netvmo::sources {
/// One camera's frames, by frame index.
class CameraStream {
 public:
  virtual ~CameraStream() = default;
  /// Frame indices are 0 .. frame_count()-1; some may be missing (has_frame() false).
  virtual int frame_count() const = 0;
  virtual bool has_frame(int frame) const = 0;
  /// The frame as 8-bit gray; an empty Mat if the camera has no image at this frame.
  /// Throws InputError naming the file if it exists but cannot be read or decoded.
  virtual cv::Mat read(int frame) = 0;
  /// The file behind a frame (image path, or "video.avi frame 12"), for messages.
  virtual std::string frame_name(int frame) const = 0;
  /// The folder or video file.
  virtual const std::filesystem::path& path() const = 0;
  /// A short name for tables: the folder's or file's name (a bag topic's name).
  virtual std::string label() const { return path().filename().string(); }
  /// Missing frames found when opening (numeric image names with gaps), ascending.
  virtual std::vector<int> missing_frames() const { return {}; }
  /// The stream's own time [s] of every frame (a video's presentation timestamps), or empty
  /// when it has none; `why_not` says why usable-looking times were refused (e.g. not
  /// increasing). May read the whole stream.
  virtual std::vector<double> own_times(std::string& why_not) {
    (void)why_not;
    return {};
  }
};

/// Image folder (png, jpg, jpeg, pgm; other files ignored). Throws InputError if the folder
/// has no images or two images share a frame number.
std::unique_ptr<CameraStream> open_image_folder(const std::filesystem::path& dir);
/// Video file via cv::VideoCapture. Throws InputError naming the file if it cannot be opened.
std::unique_ptr<CameraStream> open_video(const std::filesystem::path& file);

/// A rosbag2 bag's image topic (sensor_msgs Image or CompressedImage; ros/rosbag.hpp): frame k is
/// its k-th message as recorded, own_times() its header.stamp less `origin_ns` [s]. Throws
/// InputError naming the bag for a missing topic or a bag that cannot be read.
std::unique_ptr<CameraStream> open_bag_topic(const std::filesystem::path& bag_dir,
                                             const std::string& topic, std::int64_t origin_ns);
/// header.stamp [ns since the epoch] of a bag topic's first message (nullopt when it has none).
std::optional<std::int64_t> bag_topic_first_stamp(const std::filesystem::path& bag_dir,
                                                  const std::string& topic);

/// A kind of camera stream found in a dataset folder.
class StreamKind {
 public:
  virtual ~StreamKind() = default;
  /// e.g. "image-folder", "video"
  virtual std::string_view name() const = 0;
  /// One phrase for messages ("a folder cam_<id>/ of ... images").
  virtual std::string_view description() const = 0;
  /// The entries of this kind for camera `stem` (= "cam_<id>") in a dataset folder.
  virtual std::vector<std::filesystem::path> entries(const std::filesystem::path& dataset,
                                                     const std::string& stem) const = 0;
  /// Opens one entry that entries() returned.
  virtual std::unique_ptr<CameraStream> open(const std::filesystem::path& entry) const = 0;
};

/// The registry (observer/registry.hpp): every stream kind, in the order they are looked for.
const obs::Registry<StreamKind>& stream_kinds();

}  // namespace netvmo::sources
