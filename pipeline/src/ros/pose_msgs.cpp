#include "netvmo/pipeline/ros/pose_msgs.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "PoseStamped.h"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"
#include "ros_time.hpp"

namespace netvmo::ros {

namespace {

using Pose = geometry_msgs_msg_dds__Pose_;
using PoseStamped = geometry_msgs_msg_dds__PoseStamped_;
using PoseWithCov = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;
using TransformStamped = geometry_msgs_msg_dds__TransformStamped_;
using TfMessage = tf2_msgs_msg_dds__TFMessage_;

using detail::ns_of;
using detail::time_of;

Pose pose_of(const obs::SE3& g) {
  Pose p{};
  p.position.x = g.translation().x();
  p.position.y = g.translation().y();
  p.position.z = g.translation().z();
  const Eigen::Quaterniond q(g.linear());
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

// A unit quaternion's pose; InputError for a quaternion far from unit length.
obs::SE3 se3_of(double px, double py, double pz, double qx, double qy, double qz, double qw,
                const std::string& where) {
  const Eigen::Quaterniond q(qw, qx, qy, qz);
  if (!(std::abs(q.norm() - 1.0) < 1e-6) || !std::isfinite(px + py + pz))
    throw InputError(where + ": not a pose (finite position, unit quaternion)");
  obs::SE3 g = obs::SE3::Identity();
  g.linear() = q.normalized().toRotationMatrix();
  g.translation() = obs::Vec3(px, py, pz);
  return g;
}

// A decoded header and pose (no covariance).
StampedPose stamped_pose(const std_msgs_msg_dds__Header_& h, const Pose& p,
                         const std::string& where) {
  StampedPose out;
  out.stamp_ns = ns_of(h.stamp);
  out.frame_id = h.frame_id ? h.frame_id : "";
  out.pose = se3_of(p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
                    p.orientation.z, p.orientation.w, where);
  return out;
}

}  // namespace

std::string camera_frame(int camera_id) {
  return "cam_" + std::to_string(camera_id);
}

std::string estimate_frame(int camera_id) {
  return camera_frame(camera_id) + "/average_pose";
}

std::int64_t stamp_ns_of(double t) {
  return std::llround(t * 1e9);
}

const dds_topic_descriptor_t& pose_stamped_descriptor() {
  return geometry_msgs_msg_dds__PoseStamped__desc;
}
const dds_topic_descriptor_t& pose_with_covariance_descriptor() {
  return geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc;
}
const dds_topic_descriptor_t& tf_message_descriptor() {
  return tf2_msgs_msg_dds__TFMessage__desc;
}

void with_pose_stamped(const StampedPose& m, const std::function<void(const void*)>& use) {
  PoseStamped s{};
  s.header.stamp = time_of(m.stamp_ns);
  s.header.frame_id = const_cast<char*>(m.frame_id.c_str());
  s.pose = pose_of(m.pose);
  use(&s);
}

void with_pose_with_covariance(const StampedPose& m, const std::function<void(const void*)>& use) {
  PoseWithCov s{};
  s.header.stamp = time_of(m.stamp_ns);
  s.header.frame_id = const_cast<char*>(m.frame_id.c_str());
  s.pose.pose = pose_of(m.pose);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      s.pose.covariance[6 * r + c] = m.covariance ? (*m.covariance)(r, c) : 0.0;
  if (!m.covariance) s.pose.covariance[0] = -1.0;
  use(&s);
}

void with_tf_message(const std::vector<StampedTransform>& m,
                     const std::function<void(const void*)>& use) {
  std::vector<TransformStamped> t(m.size());
  for (size_t k = 0; k < m.size(); ++k) {
    t[k].header.stamp = time_of(m[k].stamp_ns);
    t[k].header.frame_id = const_cast<char*>(m[k].parent.c_str());
    t[k].child_frame_id = const_cast<char*>(m[k].child.c_str());
    const Pose p = pose_of(m[k].pose);
    t[k].transform.translation.x = p.position.x;
    t[k].transform.translation.y = p.position.y;
    t[k].transform.translation.z = p.position.z;
    t[k].transform.rotation = p.orientation;
  }
  TfMessage s{};
  s.transforms._length = s.transforms._maximum = static_cast<uint32_t>(t.size());
  s.transforms._buffer = t.data();
  s.transforms._release = false;
  use(&s);
}

std::vector<std::uint8_t> encode_pose_stamped(const StampedPose& m) {
  std::vector<std::uint8_t> out;
  with_pose_stamped(m, [&](const void* s) { out = encode(pose_stamped_descriptor(), s); });
  return out;
}

std::vector<std::uint8_t> encode_pose_with_covariance(const StampedPose& m) {
  std::vector<std::uint8_t> out;
  with_pose_with_covariance(
      m, [&](const void* s) { out = encode(pose_with_covariance_descriptor(), s); });
  return out;
}

std::vector<std::uint8_t> encode_tf_message(const std::vector<StampedTransform>& m) {
  std::vector<std::uint8_t> out;
  with_tf_message(m, [&](const void* s) { out = encode(tf_message_descriptor(), s); });
  return out;
}

StampedPose decode_pose_stamped(const std::vector<std::uint8_t>& msg, const std::string& where) {
  Decoded<PoseStamped> d(pose_stamped_descriptor());
  std::string why;
  if (!d.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
  return stamped_pose(d->header, d->pose, where);
}

StampedPose decode_pose_with_covariance(const std::vector<std::uint8_t>& msg,
                                        const std::string& where) {
  Decoded<PoseWithCov> d(pose_with_covariance_descriptor());
  std::string why;
  if (!d.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
  StampedPose out = stamped_pose(d->header, d->pose.pose, where);
  if (d->pose.covariance[0] != -1.0) {
    Covariance6 c;
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) c(r, k) = d->pose.covariance[6 * r + k];
    out.covariance = c;
  }
  return out;
}

std::vector<StampedTransform> decode_tf_message(const std::vector<std::uint8_t>& msg,
                                                const std::string& where) {
  Decoded<TfMessage> d(tf_message_descriptor());
  std::string why;
  if (!d.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
  std::vector<StampedTransform> out;
  for (uint32_t k = 0; k < d->transforms._length; ++k) {
    const auto& t = d->transforms._buffer[k];
    StampedTransform s;
    s.stamp_ns = ns_of(t.header.stamp);
    s.parent = t.header.frame_id ? t.header.frame_id : "";
    s.child = t.child_frame_id ? t.child_frame_id : "";
    const auto& tr = t.transform.translation;
    const auto& q = t.transform.rotation;
    s.pose = se3_of(tr.x, tr.y, tr.z, q.x, q.y, q.z, q.w, where);
    out.push_back(s);
  }
  return out;
}

}  // namespace netvmo::ros
