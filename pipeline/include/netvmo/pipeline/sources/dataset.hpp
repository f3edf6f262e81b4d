// Dataset folders: the camera network, calibrations and every camera's stream.
//
// A dataset folder (rendered by `netvmo render` or recorded) holds
//   network.yaml                        (see network_config.hpp)
//   calib/cam_<id>.yaml                 OpenCV FileStorage (also .yml), or a ROS camera_info
//                                       YAML (detected by its `distortion_model` key), or
//   calib/cam_<id>.xml                  ViSP XML (vpXmlParserCamera, camera name cam_<id>)
//   cam_<id>/ or cam_<id>.<ext>         the camera's frames: one entry of a registered stream
//                                       kind (camera_stream.hpp): an image folder (png, jpg,
//                                       jpeg, pgm) or a video file cv::VideoCapture reads
//   truth.csv, target.csv               optional ground truth (truth_io.hpp)
//   cameras.csv                         optional: every camera image's believed pose g_wi
//                                       (truth_io.hpp); a camera without rows is static at its
//                                       network.yaml pose
//   timestamps.csv                      optional: every image's time (truth_io.hpp); without
//                                       it, a video's own times or frame / fps (a note)
// or, instead of the cameras' entries, a rosbag2 bag: metadata.yaml and its .db3 files
// (ros/rosbag.hpp), each camera's frames the messages of its network.yaml `image_topic`, their
// times header.stamp less the earliest first image's, its calibration calib/ or the first
// message of its `camera_info_topic` (docs/datasets.md, "rosbag2 bags").
//
// Frame-count rule (never a silent shift of frames):
//  - Image folder, all file stems numeric (e.g. 000042.png): the number IS the frame index
//    (rendered datasets start at 0). A number absent from the folder is a missing frame: the
//    camera is blind there, and open_dataset() warns. Two files with the same number are an
//    error.
//  - Image folder, any non-numeric stem: frame index = position in the name-sorted list.
//  - Video file: frame index = position in the decoded stream (count from the container).
//  - The dataset's frame count is network.yaml's `frames` if given, otherwise the largest
//    count over the cameras at the dataset's fps. A camera at the dataset's fps with fewer
//    frames is blind after its last one (warning); frames beyond `frames` are ignored (warning).
//    A camera with its own `fps` (network.yaml) keeps all its frames, on its own clock.
//  - Times: timestamps.csv gives each image's time; a camera it lists needs a row for every
//    image it has (and none beyond its last). A camera it does not list (every camera without
//    the file) takes its video's own timestamps (CameraStream::own_times, strictly increasing;
//    within 1 ms of frame / fps they are taken as exactly that), else frame / its fps; `notes`
//    says which, per camera.
//  - A frame that exists but cannot be decoded is an InputError naming the file (and frame for
//    videos), thrown by read(); callers may treat that camera as blind for that frame.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/sources/camera_stream.hpp"

namespace netvmo::sources {

struct DatasetCamera {
  int id = 0;
  io::Calibration calib;
  std::unique_ptr<CameraStream> source;
  /// Image times from timestamps.csv, by frame (NaN where a missing frame has no row); empty:
  /// frame / fps.
  std::vector<double> times;
  /// Believed poses g_wi from cameras.csv, by frame; empty: static at network.yaml's pose.
  std::vector<obs::SE3> poses;
};

struct Dataset {
  std::filesystem::path dir;
  io::NetworkConfig network;
  std::vector<DatasetCamera> cameras;  ///< in network.yaml order
  int frame_count = 0;                 ///< see the frame-count rule above
  std::vector<std::string> warnings;   ///< one line each, for the user
  std::vector<std::string> notes;      ///< information for the log (e.g. where times come from)

  /// Camera `camera_index` (position in `cameras`) at `frame`: 8-bit gray, or empty when the
  /// camera is blind there (missing frame, after its last frame). Throws InputError naming the
  /// file if the image is unreadable or its size differs from the calibration.
  cv::Mat read(size_t camera_index, int frame);
  /// Index of a camera id in `cameras`, or -1.
  int index_of(int camera_id) const { return network.index_of(camera_id); }
  /// The frames of camera `camera_index`: frame_count at the dataset's fps, its own stream's
  /// count when it has its own fps (0 for a camera that was not opened).
  int camera_frame_count(size_t camera_index) const;
  /// The time [s] of camera `camera_index`'s image `frame`: timestamps.csv's, else
  /// frame / the camera's fps (also for frames past its last image).
  double frame_time(size_t camera_index, int frame) const;
  /// timestamps.csv's time of that image, when the file gives one.
  std::optional<double> listed_time(size_t camera_index, int frame) const;
  /// Believed pose of camera `camera_index` at `frame`: cameras.csv's (its last row past its
  /// last image), else network.yaml's.
  obs::SE3 camera_pose(size_t camera_index, int frame) const;
};

/// Camera `camera_id`'s calibration in `dir`/calib (cam_<id>.yaml, .yml or .xml, in that order;
/// the formats above), or nothing when there is none. Throws InputError naming a bad file.
std::optional<io::Calibration> find_calibration(const std::filesystem::path& dir, int camera_id);
/// The one-line message for a camera without a calibration file in `dir`/calib.
std::string calibration_not_found(const std::filesystem::path& dir, int camera_id);

/// Opens a dataset folder: network.yaml, then for every camera its calibration and its image
/// folder or video. Throws InputError naming the offending file (missing calibration, no
/// images or video for a declared camera, both a folder and a video, ...). With `only_camera`
/// (a camera id), the other cameras keep their network.yaml entry but neither their calibration
/// nor their frames are opened (a camera's own process); reading them throws InputError.
/// With `keep_going`, a camera whose video or image folder cannot be opened at all (e.g. a
/// truncated MP4) is blind for the whole run, with one warning, instead of an InputError.
Dataset open_dataset(const std::filesystem::path& dir, std::optional<int> only_camera = {},
                     bool keep_going = false);

}  // namespace netvmo::sources
