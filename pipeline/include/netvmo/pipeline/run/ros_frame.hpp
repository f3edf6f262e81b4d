// One camera's frame as ROS 2 messages (docs/ros2.md), written once for the node's live topics
// (net::RosPublisher) and a run's bag (run --bag): its measurement (the tag's PnP pose in the
// camera frame with frontend::pnp_covariance), its estimate of the average target pose in the
// world frame with obs::neighbour_spread as covariance, and the estimate's transform.
#pragma once

#include <optional>
#include <vector>

#include "netvmo/pipeline/ros/pose_msgs.hpp"
#include "netvmo/pipeline/run/camera_step.hpp"

namespace netvmo::run {

struct RosFrame {
  std::optional<ros::StampedPose> measurement;   ///< when the camera has a PnP pose
  std::optional<ros::StampedPose> average_pose;  ///< when the camera has an estimate
  std::vector<ros::StampedTransform> tf;         ///< world -> cam_<id>/average_pose
};

/// Camera `camera_id`'s messages at time t [s]: `cam` its front end's output, `estimate_w` its
/// estimate of the average pose (world frame) when it has one, `neighbours_w` its neighbours'
/// latest estimates (for the covariance).
RosFrame ros_frame(int camera_id, double t, const frontend::Observation& cam,
                   const std::optional<obs::SE3>& estimate_w,
                   const std::vector<obs::SE3>& neighbours_w);

/// The rig's static transform of a camera: world -> cam_<id>, its believed pose g_wi.
ros::StampedTransform camera_transform(int camera_id, double t, const obs::SE3& g_wi);

}  // namespace netvmo::run
