// A dataset folder written as a rosbag2 bag (ros/rosbag.hpp), the form ROS 2 users record, which
// every command that takes a dataset folder also takes (dataset.hpp): `netvmo bag`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::sources {

struct BagExportSettings {
  /// How the images are stored: mono8 or rgb8 (sensor_msgs/msg/Image on /cam_<id>/image_raw),
  /// png or jpeg (sensor_msgs/msg/CompressedImage on /cam_<id>/image_raw/compressed).
  std::string encoding = "mono8";
  /// Each camera's calibration as a sensor_msgs/msg/CameraInfo on /cam_<id>/camera_info (one
  /// message, at its first image); false: calib/ is copied instead.
  bool camera_info = true;
  /// header.stamp of the dataset's time 0 [ns since the epoch]: 2023-11-14 22:13:20 UTC.
  std::int64_t stamp_origin_ns = 1'700'000'000'000'000'000;
};

/// Writes `ds` as a bag into the empty or new folder `out`: metadata.yaml and bag_0.db3 with every
/// camera's images in time order (header.stamp and the bag's timestamp: stamp_origin_ns plus the
/// image's time), network.yaml naming each camera's topics, and truth.csv, target.csv,
/// cameras.csv and truth_cameras.csv where the dataset has them. A camera's missing frames are left
/// out of its topic (frame indices then shift: a bag has no gaps). Returns the number of image
/// messages.
int write_bag(Dataset& ds, const std::filesystem::path& out, const BagExportSettings& s = {});

}  // namespace netvmo::sources
