// A live camera network: a folder with network.yaml, whose cameras name their ROS 2 image topics
// (`image_topic:`, optionally `camera_info_topic:`), and calib/ for the cameras that name no
// camera_info_topic, but no images (`netvmo node --live`, `netvmo launch --live`; docs/ros2.md,
// "Live camera topics"). Its frames are appended as they arrive (net::LiveCamera) and each is
// read once. A live launch's merge has its nodes' rows as the only record of the images
// (net::merge_nodes).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::sources {

class TopicNetwork : public NetworkSource {
 public:
  /// Reads `dir`/network.yaml and the calib/ file of each camera that has one (of `only_camera`
  /// alone when given). Throws InputError naming the file.
  explicit TopicNetwork(const std::filesystem::path& dir, std::optional<int> only_camera = {});

  const io::NetworkConfig& network() const override { return net_; }
  /// Throws InputError when the camera has no calibration (yet: set_calibration).
  const io::Calibration& calibration(size_t camera_index) const override;
  bool has_calibration(size_t camera_index) const { return calib_.at(camera_index).has_value(); }
  void set_calibration(size_t camera_index, io::Calibration calib);
  /// The camera's image topic: network.yaml's `image_topic`. Throws InputError naming
  /// network.yaml's key when it names none.
  std::string image_topic(size_t camera_index) const;

  /// The image of camera `camera_index` at time `t` [s] becomes its next frame. Throws
  /// InputError (naming `where`) when its size differs from the calibration.
  void append(size_t camera_index, double t, cv::Mat image, const std::string& where);

  /// The most frames of any camera so far.
  int frame_count() const override;
  int camera_frame_count(size_t camera_index) const override;
  std::optional<double> listed_time(size_t camera_index, int frame) const override;
  /// The appended image (once: the source keeps no image it has handed out); empty when the
  /// camera has no image there.
  cv::Mat read(size_t camera_index, int frame) override;
  std::optional<obs::SE3> target_truth(int, size_t = 0) const override { return std::nullopt; }
  std::optional<obs::SE3> camera_truth(size_t, int) const override { return std::nullopt; }
  std::string name() const override { return dir_.string(); }

 private:
  std::filesystem::path dir_;
  io::NetworkConfig net_;
  std::vector<std::optional<io::Calibration>> calib_;
  std::vector<std::vector<double>> times_;
  std::vector<std::vector<cv::Mat>> images_;
};

/// Whether `dir` is a live network's folder: network.yaml names an image_topic for some camera
/// and `dir` is not a rosbag2 bag (no metadata.yaml).
bool is_topic_network(const std::filesystem::path& dir);

}  // namespace netvmo::sources
