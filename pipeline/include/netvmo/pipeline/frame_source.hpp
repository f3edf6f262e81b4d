// Frame sources (image folders and video files) and dataset folders.
//
// A dataset folder (rendered by `netvmo render` or recorded) holds
//   network.yaml                        (see network_config.hpp)
//   calib/cam_<id>.yaml                 OpenCV FileStorage (also .yml), or
//   calib/cam_<id>.xml                  ViSP XML (vpXmlParserCamera, camera name cam_<id>)
//   cam_<id>/                           images (png, jpg, jpeg, pgm), or
//   cam_<id>.<ext>                      a video file cv::VideoCapture reads (avi, mp4, mkv, ...)
//   truth.csv, target.csv               optional ground truth (truth_io.hpp)
//
// Frame-count rule (never a silent shift of frames):
//  - Image folder, all file stems numeric (e.g. 000042.png): the number IS the frame index
//    (rendered datasets start at 0). A number absent from the folder is a missing frame: the
//    camera is blind there, and open_dataset() warns. Two files with the same number are an
//    error.
//  - Image folder, any non-numeric stem: frame index = position in the name-sorted list.
//  - Video file: frame index = position in the decoded stream (count from the container).
//  - The dataset's frame count is network.yaml's `frames` if given, otherwise the largest
//    count over the cameras. A camera with fewer frames is blind after its last one (warning);
//    frames beyond `frames` are ignored (warning).
//  - A frame that exists but cannot be decoded is an InputError naming the file (and frame for
//    videos), thrown by read(); callers may treat that camera as blind for that frame.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "netvmo/pipeline/calibration.hpp"
#include "netvmo/pipeline/network_config.hpp"

namespace netvmo::pipeline {

/// One camera's frames.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
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
  /// Missing frames found when opening (numeric image names with gaps), ascending.
  virtual std::vector<int> missing_frames() const { return {}; }
};

/// Image folder (png, jpg, jpeg, pgm; other files ignored). Throws InputError if the folder
/// has no images or two images share a frame number.
std::unique_ptr<FrameSource> open_image_folder(const std::filesystem::path& dir);
/// Video file via cv::VideoCapture. Throws InputError naming the file if it cannot be opened.
std::unique_ptr<FrameSource> open_video(const std::filesystem::path& file);

struct DatasetCamera {
  int id = 0;
  Calibration calib;
  std::unique_ptr<FrameSource> source;
};

struct Dataset {
  std::filesystem::path dir;
  NetworkConfig network;
  std::vector<DatasetCamera> cameras;  ///< in network.yaml order
  int frame_count = 0;                 ///< see the frame-count rule above
  std::vector<std::string> warnings;   ///< one line each, for the user

  /// Camera `camera_index` (position in `cameras`) at `frame`: 8-bit gray, or empty when the
  /// camera is blind there (missing frame, after its last frame). Throws InputError naming the
  /// file if the image is unreadable or its size differs from the calibration.
  cv::Mat read(size_t camera_index, int frame);
  /// Index of a camera id in `cameras`, or -1.
  int index_of(int camera_id) const { return network.index_of(camera_id); }
};

/// Opens a dataset folder: network.yaml, then for every camera its calibration and its image
/// folder or video. Throws InputError naming the offending file (missing calibration, no
/// images or video for a declared camera, both a folder and a video, ...). With `only_camera`
/// (a camera id), the other cameras keep their network.yaml entry but neither their calibration
/// nor their frames are opened (a camera's own process); reading them throws InputError.
Dataset open_dataset(const std::filesystem::path& dir, std::optional<int> only_camera = {});

}  // namespace netvmo::pipeline
