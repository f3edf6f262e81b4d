// `netvmo run --bag OUT`: a run written as a rosbag2 bag (sqlite3 storage, ros/rosbag.hpp) that
// `ros2 bag info`, `ros2 bag play` and Foxglove open, with the same messages a node publishes
// live (run/ros_frame.hpp, net/ros_publisher.hpp; docs/ros2.md), per camera <id>:
//   /netvmo/camera_<id>/overlay/compressed   sensor_msgs/msg/CompressedImage (JPEG): the overlay
//   /netvmo/camera_<id>/camera_info          sensor_msgs/msg/CameraInfo
//   /netvmo/camera_<id>/measurement          geometry_msgs/msg/PoseWithCovarianceStamped
//   /netvmo/camera_<id>/average_pose         geometry_msgs/msg/PoseStamped
//   /netvmo/camera_<id>/average_pose_with_covariance   PoseWithCovarianceStamped
// and /tf (each estimate; a moving camera's pose) and /tf_static (the static cameras' poses,
// once), stamped with the frame's time. The first target only (network.yaml `targets:`).
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::run {

struct BagSettings {
  /// The overlays are drawn at most this wide [px] (scaled down from wider images; 0: full
  /// resolution).
  int overlay_max_width = 1280;
  int jpeg_quality = 90;  ///< of the overlay images
};

class BagRecorder {
 public:
  /// Writes into `dir`, which must not exist or be empty (RosBagWriter).
  BagRecorder(const std::filesystem::path& dir, const sources::World& world,
              BagSettings settings = {});
  ~BagRecorder();
  BagRecorder(const BagRecorder&) = delete;
  BagRecorder& operator=(const BagRecorder&) = delete;
  /// A FrameHook: cams [target][camera], one record per target.
  void operator()(int frame, const std::vector<cv::Mat>& images,
                  const std::vector<std::vector<frontend::Observation>>& cams,
                  const std::vector<const run::FrameRecord*>& records);
  /// Commits the bag and writes metadata.yaml.
  void finish();

 private:
  struct Topics {
    int overlay = 0, info = 0, measurement = 0, pose = 0, pose_cov = 0;
  };
  const sources::World& world_;
  BagSettings settings_;
  obs::Graph graph_;
  ros::RosBagWriter bag_;
  std::vector<Topics> topics_;
  int tf_ = 0, tf_static_ = 0;
  bool statics_written_ = false;
};

}  // namespace netvmo::run
