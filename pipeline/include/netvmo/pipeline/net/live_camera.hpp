// One camera's live ROS 2 image stream over Cyclone DDS (`netvmo node --live`): its
// sensor_msgs/msg/Image or CompressedImage topic (a name ending in /compressed, as
// image_transport names it) read best-effort, which matches best-effort and reliable
// publishers alike, keeping every sample until taken; and, for a camera without a calib/ file,
// its calibration from the first sensor_msgs/msg/CameraInfo of its camera_info_topic. Images
// become the camera's frames in a sources::TopicNetwork, on their header.stamp.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "netvmo/pipeline/net/ros_publisher.hpp"
#include "netvmo/pipeline/sources/topic_network.hpp"

namespace netvmo::net {

/// When a live stream ends, and how far behind its images a node runs. Defaults are `netvmo
/// node`'s and `netvmo launch --live`'s.
struct LiveSettings {
  /// The ROS 2 topics (e.g. /cam_1/image_raw); empty: network.yaml's image_topic (and
  /// camera_info_topic) of the camera.
  std::string image_topic, camera_info_topic;
  /// The stream ends at its first image this long [s of image time] after its first image;
  /// 0: no bound.
  double duration_s = 0.0;
  /// The stream ends when no image has come for this long [s, wall clock].
  double idle_s = 2.0;
  /// A node runs this far [s, wall clock] behind its images: frame k is integrated once image
  /// k+1 has come (its length is then known), so `lag_s` covers one frame interval and the
  /// delivery; a later image holds the node back until it comes.
  double lag_s = 0.1;
};

/// The DDS topic of a ROS 2 topic name ("/cam_1/image_raw" -> "rt/cam_1/image_raw").
std::string dds_topic_of(const std::string& ros_topic);

class LiveCamera {
 public:
  /// Subscribes to camera `camera_index`'s topics of `network` (not owned) on `domain`.
  /// Throws InputError when the camera names no image topic (settings' or network.yaml's).
  LiveCamera(int domain, sources::TopicNetwork& network, size_t camera_index,
             const LiveSettings& settings, const SecurityIdentity* security = nullptr);
  ~LiveCamera();
  LiveCamera(const LiveCamera&) = delete;
  LiveCamera& operator=(const LiveCamera&) = delete;

  /// Makes sure the camera's image `frame` is in the network, appending the images that came in
  /// stamp order; false once the stream has ended before it (idle, or past the duration).
  /// `first_timeout_s` bounds the wait for the first image (then InputError naming the topic).
  /// Throws InputError naming the topic for an image that cannot be decoded or does not match
  /// the calibration.
  bool wait_frame(int frame, double first_timeout_s);
  /// The wall clock [s since the epoch] when the first image was taken.
  double first_wall() const { return first_wall_; }
  const std::string& image_topic() const { return image_topic_; }
  /// Images whose stamp was not after the previous one's (dropped).
  std::uint64_t out_of_order() const { return out_of_order_; }

 private:
  bool take_images(double timeout_s);

  sources::TopicNetwork& net_;
  size_t index_;
  LiveSettings settings_;
  std::string image_topic_, info_topic_, image_type_;
  std::unique_ptr<RosTopicReader> images_, infos_;
  std::vector<std::vector<std::uint8_t>> pending_;  ///< images taken before the calibration
  double first_wall_ = 0.0, last_wall_ = 0.0;
  std::optional<double> first_stamp_, last_stamp_;
  bool ended_ = false;
  std::uint64_t received_ = 0, out_of_order_ = 0;
};

}  // namespace netvmo::net
