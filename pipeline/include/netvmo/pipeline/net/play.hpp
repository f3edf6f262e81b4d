// `netvmo play`: a dataset folder or bag published as ROS 2 camera topics over Cyclone DDS, as a
// camera driver would (docs/ros2.md, "Playing a dataset"): per camera <id>
//   rt/cam_<id>/image_raw              sensor_msgs/msg/Image (mono8 or rgb8), or
//   rt/cam_<id>/image_raw/compressed   sensor_msgs/msg/CompressedImage (jpeg or png)
//   rt/cam_<id>/camera_info            sensor_msgs/msg/CameraInfo
// (the topics `netvmo bag` writes), every image at its time in the dataset (timestamps.csv's; a
// bag's stamps less the earliest first one; else frame / fps) scaled by the rate, header.stamp
// that time, frame_id cam_<id>.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "netvmo/pipeline/net/security.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::net {

struct PlaySettings {
  int domain = 0;
  /// Playback speed: 1 real time, 2 twice as fast; 0 as fast as the writers go.
  double rate = 1.0;
  std::string encoding = "mono8";  ///< mono8, rgb8 (Image) or jpeg, png (CompressedImage)
  /// Reliable writers (keep last 5); default best-effort, ROS 2's sensor-data QoS that camera
  /// drivers use. A reliable reader does not match a best-effort writer; a best-effort reader
  /// matches both.
  bool reliable = false;
  bool camera_info = true;
  /// Before the first image, wait until this many readers match every camera's image topic
  /// (bounded by timeout_s; then InputError). 0: start at once.
  int wait_readers = 0;
  double timeout_s = 30.0;
  /// Where a best-effort reader matches an image or camera_info writer when the first image is
  /// due, play waits this long [s] before it: such a reader must itself have discovered play's
  /// writers to take their samples, and it acknowledges nothing, so play cannot see that (a
  /// live node's reader missed the first image in 8 of 40 plays under load without the wait,
  /// none with 0.25 s; docs/ros2.md). 0: no wait.
  double settle_s = 0.25;
  /// After the last image, the writers stay until reliable readers acknowledge, at most this
  /// long [s], and, where a best-effort reader (which acknowledges nothing) matches any of them,
  /// this long in any case, so that it receives the last images whole.
  double linger_s = 2.0;
  /// DDS Security: the identity to publish with (a security folder's `player`); none: unsecured.
  std::optional<SecurityIdentity> security;
};

struct PlayStats {
  int images = 0;        ///< image messages written
  double seconds = 0.0;  ///< wall time from the first image to the last
  double late_s = 0.0;   ///< the largest delay behind schedule of an image [s]
};

/// Publishes every image of `source` (all cameras, in time order). `progress` (optional) is
/// called after each image with (done, total). Throws InputError for a bad encoding, an
/// unreadable image or readers that do not come, std::runtime_error when Cyclone DDS refuses.
PlayStats play(sources::NetworkSource& source, const PlaySettings& settings,
               const std::function<void(int, int)>& progress = {});

}  // namespace netvmo::net
