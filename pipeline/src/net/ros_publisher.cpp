#include "netvmo/pipeline/net/ros_publisher.hpp"

#include <chrono>
#include <stdexcept>

#include "dds_util.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"

namespace netvmo::net {

namespace {

using detail::check;

dds_entity_t make_writer(dds_entity_t participant, const std::string& name,
                         const dds_topic_descriptor_t& type, bool tf_static, std::int32_t depth) {
  const dds_entity_t topic = check(
      dds_create_topic(participant, &type, name.c_str(), nullptr, nullptr), "create ROS topic");
  dds_qos_t* q = ros_topic_qos(tf_static, depth);
  const dds_entity_t w = dds_create_writer(participant, topic, q, nullptr);
  dds_delete_qos(q);
  return check(w, "create ROS writer");
}

}  // namespace

dds_qos_t* ros_topic_qos(bool tf_static, std::int32_t depth) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  if (tf_static) {
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  } else {
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  }
  return q;
}

RosPublisher::RosPublisher(dds_entity_t participant, int camera_id) {
  const std::string prefix = "rt/netvmo/camera_" + std::to_string(camera_id);
  pose_ =
      make_writer(participant, prefix + "/average_pose", ros::pose_stamped_descriptor(), false, 10);
  pose_cov_ = make_writer(participant, prefix + "/average_pose_with_covariance",
                          ros::pose_with_covariance_descriptor(), false, 10);
  measurement_ = make_writer(participant, prefix + "/measurement",
                             ros::pose_with_covariance_descriptor(), false, 10);
  tf_ = make_writer(participant, "rt/tf", ros::tf_message_descriptor(), false, 100);
  tf_static_ = make_writer(participant, "rt/tf_static", ros::tf_message_descriptor(), true, 1);
}

RosPublisher::~RosPublisher() {
  for (dds_entity_t w : {pose_, pose_cov_, measurement_, tf_, tf_static_})
    if (w > 0) dds_delete(w);
}

void RosPublisher::average_pose(const ros::StampedPose& m) {
  ros::with_pose_stamped(m, [&](const void* s) { check(dds_write(pose_, s), "write pose"); });
  ros::with_pose_with_covariance(
      m, [&](const void* s) { check(dds_write(pose_cov_, s), "write pose with covariance"); });
}

void RosPublisher::measurement(const ros::StampedPose& m) {
  ros::with_pose_with_covariance(
      m, [&](const void* s) { check(dds_write(measurement_, s), "write measurement"); });
}

void RosPublisher::tf(const std::vector<ros::StampedTransform>& m) {
  ros::with_tf_message(m, [&](const void* s) { check(dds_write(tf_, s), "write tf"); });
}

void RosPublisher::tf_static(const std::vector<ros::StampedTransform>& m) {
  ros::with_tf_message(m,
                       [&](const void* s) { check(dds_write(tf_static_, s), "write tf_static"); });
}

bool RosPublisher::wait_pose_readers(int n, double timeout_s) const {
  return detail::wait_for_readers({pose_}, n, timeout_s);
}

RosTopicReader::RosTopicReader(int domain, const std::string& dds_topic,
                               const dds_topic_descriptor_t& type, bool tf_static, bool reliable,
                               const SecurityIdentity* security)
    : type_(type) {
  participant_ = create_participant(domain, security, "create participant (check CYCLONEDDS_URI)");
  try {
    topic_ = check(dds_create_topic(participant_, &type, dds_topic.c_str(), nullptr, nullptr),
                   "create ROS topic");
    // Every sample of every writer (a keyless topic with several writers, as rt/tf_static, keeps
    // one sample in all at depth 1).
    dds_qos_t* q = ros_topic_qos(tf_static, 0);
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    if (!reliable) dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
    reader_ = dds_create_reader(participant_, topic_, q, nullptr);
    dds_delete_qos(q);
    check(reader_, "create ROS reader");
    detail::make_waitset(participant_, reader_, readcond_, waitset_);
  } catch (...) {
    dds_delete(participant_);
    throw;
  }
}

RosTopicReader::~RosTopicReader() {
  dds_delete(participant_);
}

int RosTopicReader::matched_writers() const {
  dds_subscription_matched_status_t st;
  check(dds_get_subscription_matched_status(reader_, &st), "matched status");
  return static_cast<int>(st.current_count);
}

std::vector<std::vector<std::uint8_t>> RosTopicReader::take(double timeout_s) {
  std::vector<std::vector<std::uint8_t>> out;
  const auto t0 = std::chrono::steady_clock::now();
  constexpr int kMax = 64;
  for (;;) {
    void* samples[kMax] = {nullptr};
    dds_sample_info_t infos[kMax];
    const dds_return_t n = dds_take(reader_, samples, infos, kMax, kMax);
    check(n, "take");
    for (dds_return_t k = 0; k < n; ++k)
      if (infos[k].valid_data) out.push_back(ros::encode(type_, samples[k]));
    if (n > 0) dds_return_loan(reader_, samples, n);
    if (n == kMax) continue;
    const double left =
        timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!out.empty() || left <= 0) return out;
    check(dds_waitset_wait(waitset_, nullptr, 0, static_cast<dds_duration_t>(left * 1e9)), "wait");
  }
}

}  // namespace netvmo::net
