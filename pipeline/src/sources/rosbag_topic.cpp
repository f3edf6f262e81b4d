// A camera's images from a rosbag2 bag's topic (sensor_msgs Image or CompressedImage): frame k
// is the topic's k-th message in recording order, its time header.stamp less the dataset's
// origin (sources/dataset.hpp).
#include <cmath>
#include <cstdint>
#include <optional>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"
#include "netvmo/pipeline/sources/camera_stream.hpp"
#include "stream_util.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;

namespace {

// Enough of a message for its header: the encapsulation, the stamp and a frame_id of up to
// 240 characters (a longer one is read whole).
constexpr std::size_t kHeaderBytes = 256;

class BagTopicStream : public CameraStream {
 public:
  BagTopicStream(const fs::path& dir, std::string topic, std::int64_t origin_ns)
      : bag_(dir),
        topic_(std::move(topic)),
        origin_ns_(origin_ns),
        name_(dir.string() + ":" + topic_) {
    const ros::BagTopic* t = bag_.find_topic(topic_);
    if (!t) throw InputError(name_.string() + ": no such topic in the bag");
    type_ = t->type;
    messages_ = bag_.messages(topic_);
  }
  int frame_count() const override { return static_cast<int>(messages_.size()); }
  bool has_frame(int f) const override { return f >= 0 && f < frame_count(); }
  cv::Mat read(int f) override {
    if (!has_frame(f)) return {};
    const auto& m = messages_[static_cast<size_t>(f)];
    return ros::decode_gray(type_, bag_.read(m), frame_name(f));
  }
  std::string frame_name(int f) const override {
    if (!has_frame(f)) return name_.string() + " message " + std::to_string(f) + " (none)";
    return name_.string() + " message " + std::to_string(f) + " (" +
           bag_.where(messages_[static_cast<size_t>(f)]) + ")";
  }
  const fs::path& path() const override { return name_; }
  std::string label() const override { return topic_; }
  std::vector<double> own_times(std::string& why_not) override {
    std::vector<double> t;
    for (int f = 0; f < frame_count(); ++f) {
      const std::int64_t stamp = header_stamp(messages_[static_cast<size_t>(f)], frame_name(f));
      const double time = 1e-9 * static_cast<double>(stamp - origin_ns_);
      if (!t.empty() && !(time > t.back())) {
        why_not = "header.stamp of message " + std::to_string(f) + " is not after the one before";
        return {};
      }
      t.push_back(time);
    }
    return t;
  }
  /// header.stamp [ns] of the first message (nullopt for an empty topic).
  std::optional<std::int64_t> first_stamp() {
    if (messages_.empty()) return std::nullopt;
    return header_stamp(messages_[0], frame_name(0));
  }

 private:
  std::int64_t header_stamp(const ros::BagMessageRef& m, const std::string& where) const {
    std::string why;
    auto head = bag_.read(m, kHeaderBytes);
    auto t = ros::header_stamp_ns(head.data(), head.size(), why);
    if (!t && head.size() == kHeaderBytes) {
      head = bag_.read(m);
      t = ros::header_stamp_ns(head.data(), head.size(), why);
    }
    if (!t) throw InputError(where + ": header: " + why);
    return *t;
  }

  ros::RosBag bag_;
  std::string topic_, type_;
  std::int64_t origin_ns_;
  fs::path name_;
  std::vector<ros::BagMessageRef> messages_;
};

}  // namespace

std::unique_ptr<CameraStream> open_bag_topic(const fs::path& bag_dir, const std::string& topic,
                                             std::int64_t origin_ns) {
  return std::make_unique<BagTopicStream>(bag_dir, topic, origin_ns);
}

std::optional<std::int64_t> bag_topic_first_stamp(const fs::path& bag_dir,
                                                  const std::string& topic) {
  BagTopicStream s(bag_dir, topic, 0.0);
  return s.first_stamp();
}

}  // namespace netvmo::sources
