// What a camera's node publishes for ROS 2 tools (RViz2, Foxglove, ros2 topic echo), on its
// transport's DDS participant, under the topic and type names ROS 2 uses (docs/ros2.md):
//   rt/netvmo/camera_<id>/average_pose                  geometry_msgs/msg/PoseStamped, "world"
//   rt/netvmo/camera_<id>/average_pose_with_covariance  PoseWithCovarianceStamped, "world": the
//       estimate with obs::neighbour_spread as its covariance
//   rt/netvmo/camera_<id>/measurement                   PoseWithCovarianceStamped,
//       "netvmo/camera_<id>": the tag's PnP pose in the camera with frontend::pnp_covariance, in
//       the frames where the camera detects the target
//   rt/tf_static  tf2_msgs/msg/TFMessage: world -> netvmo/camera_<id>, the camera's believed
//       pose (a static camera; reliable, transient-local, depth 1, as tf2's static broadcaster)
//   rt/tf         tf2_msgs/msg/TFMessage: world -> netvmo/camera_<id>/average_pose every frame,
//       and world -> netvmo/camera_<id> for a moving camera
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <string>
#include <vector>

#include "netvmo/pipeline/net/security.hpp"
#include "netvmo/pipeline/ros/pose_msgs.hpp"

namespace netvmo::net {

class RosPublisher {
 public:
  /// Creates the topics and writers on `participant` (not owned) for camera `camera_id`.
  /// Throws std::runtime_error when Cyclone DDS refuses.
  RosPublisher(dds_entity_t participant, int camera_id);
  ~RosPublisher();
  RosPublisher(const RosPublisher&) = delete;
  RosPublisher& operator=(const RosPublisher&) = delete;

  void average_pose(const ros::StampedPose& m);  ///< PoseStamped and PoseWithCovarianceStamped
  void measurement(const ros::StampedPose& m);
  void tf(const std::vector<ros::StampedTransform>& m);
  void tf_static(const std::vector<ros::StampedTransform>& m);
  /// Waits until at least `n` readers match the average_pose topic, at most `timeout_s`;
  /// false when they did not come.
  bool wait_pose_readers(int n, double timeout_s) const;

 private:
  dds_entity_t pose_ = 0, pose_cov_ = 0, measurement_ = 0, tf_ = 0, tf_static_ = 0;
};

/// The QoS of rt/tf_static (reliable, transient-local, keep last 1) or of the other topics
/// (reliable, volatile, keep last `depth`), for readers that match RosPublisher's writers.
/// The caller deletes it (dds_delete_qos).
dds_qos_t* ros_topic_qos(bool tf_static, std::int32_t depth);

/// A subscriber of its own (tests, tools): every message on one ROS 2 topic, as CDR bytes (for
/// ros::decode_*), from a participant of its own on `domain`; `tf_static`: transient-local;
/// `reliable` false: best-effort, which also matches best-effort writers (camera drivers).
class RosTopicReader {
 public:
  /// `security`: the participant's identity (none: unsecured).
  RosTopicReader(int domain, const std::string& dds_topic, const dds_topic_descriptor_t& type,
                 bool tf_static = false, bool reliable = true,
                 const SecurityIdentity* security = nullptr);
  ~RosTopicReader();
  RosTopicReader(const RosTopicReader&) = delete;
  RosTopicReader& operator=(const RosTopicReader&) = delete;
  /// Every message that arrived within `timeout_s` (returns early once some have).
  std::vector<std::vector<std::uint8_t>> take(double timeout_s);
  /// Writers currently matched.
  int matched_writers() const;

 private:
  const dds_topic_descriptor_t& type_;
  dds_entity_t participant_ = 0, topic_ = 0, reader_ = 0, waitset_ = 0, readcond_ = 0;
};

}  // namespace netvmo::net
