// ROS 2 pose and transform messages (geometry_msgs/msg/PoseStamped, PoseWithCovarianceStamped,
// tf2_msgs/msg/TFMessage) from netvmo's poses: the same idlc structs (pipeline/idl/PoseStamped.idl)
// serve a DDS writer (net::RosPublisher) and a bag (CDR bytes, cdr.hpp), so both carry the same
// messages. Conventions (docs/ros2.md): a pose is a frame's pose in its header's frame, the
// covariance is 6x6 row-major in (x, y, z, rotation about X, Y, Z) of that header frame
// (frontend::PoseCovariance), and an unknown covariance is all zeros but element 0, which is -1
// (sensor_msgs' convention for "not known").
#pragma once

#include <dds/dds.h>

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::ros {

inline constexpr const char* kPoseStampedType = "geometry_msgs/msg/PoseStamped";
inline constexpr const char* kPoseWithCovarianceStampedType =
    "geometry_msgs/msg/PoseWithCovarianceStamped";
inline constexpr const char* kTfMessageType = "tf2_msgs/msg/TFMessage";

using Covariance6 = Eigen::Matrix<double, 6, 6>;

/// The frames netvmo names (docs/ros2.md): the world, camera <id>'s optical frame (x right, y
/// down, z forward: netvmo's camera frame, also the frame_id of its images in a bag that
/// `netvmo bag` writes) and camera <id>'s estimate of the average target pose.
inline constexpr const char* kWorldFrame = "world";
std::string camera_frame(int camera_id);    ///< "cam_<id>"
std::string estimate_frame(int camera_id);  ///< "cam_<id>/average_pose"

/// A frame's pose in its header's frame at a time, with its covariance when it has one.
struct StampedPose {
  std::int64_t stamp_ns = 0;  ///< header.stamp [ns]
  std::string frame_id;       ///< header.frame_id
  obs::SE3 pose = obs::SE3::Identity();
  /// PoseWithCovarianceStamped's covariance; nullopt: unknown (element 0 = -1 on the wire).
  std::optional<Covariance6> covariance;
};

/// One transform of a TFMessage: the pose of `child` in `parent`.
struct StampedTransform {
  std::int64_t stamp_ns = 0;
  std::string parent, child;
  obs::SE3 pose = obs::SE3::Identity();
};

/// Seconds (a run's time) as header.stamp nanoseconds, rounded to the nearest.
std::int64_t stamp_ns_of(double t);

/// The idlc descriptors, for topics of these types.
const dds_topic_descriptor_t& pose_stamped_descriptor();
const dds_topic_descriptor_t& pose_with_covariance_descriptor();
const dds_topic_descriptor_t& tf_message_descriptor();

/// Calls `use` with the message as its idlc struct (valid during the call only): for dds_write.
void with_pose_stamped(const StampedPose& m, const std::function<void(const void*)>& use);
void with_pose_with_covariance(const StampedPose& m, const std::function<void(const void*)>& use);
void with_tf_message(const std::vector<StampedTransform>& m,
                     const std::function<void(const void*)>& use);

/// The same messages serialized (CDR_LE, as ROS 2 writes them): for a bag.
std::vector<std::uint8_t> encode_pose_stamped(const StampedPose& m);
std::vector<std::uint8_t> encode_pose_with_covariance(const StampedPose& m);
std::vector<std::uint8_t> encode_tf_message(const std::vector<StampedTransform>& m);

/// Read back (tests, tools). Throws InputError(where + ": ...") for a malformed message.
StampedPose decode_pose_stamped(const std::vector<std::uint8_t>& msg, const std::string& where);
StampedPose decode_pose_with_covariance(const std::vector<std::uint8_t>& msg,
                                        const std::string& where);
std::vector<StampedTransform> decode_tf_message(const std::vector<std::uint8_t>& msg,
                                                const std::string& where);

}  // namespace netvmo::ros
