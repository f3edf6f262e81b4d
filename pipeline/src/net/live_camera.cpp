#include "netvmo/pipeline/net/live_camera.hpp"

#include <algorithm>
#include <chrono>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"
#include "netvmo/pipeline/net/socket_drops.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::net {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

std::string dds_topic_of(const std::string& ros_topic) {
  return "rt" + (ros_topic.rfind('/', 0) == 0 ? ros_topic : "/" + ros_topic);
}

LiveCamera::LiveCamera(int domain, sources::TopicNetwork& network, size_t camera_index,
                       const LiveSettings& settings, const SecurityIdentity* security)
    : net_(network), index_(camera_index), settings_(settings) {
  const auto& cam = net_.network().cameras.at(camera_index);
  image_topic_ =
      settings.image_topic.empty() ? net_.image_topic(camera_index) : settings.image_topic;
  info_topic_ = !settings.camera_info_topic.empty() ? settings.camera_info_topic
                : settings.image_topic.empty()      ? cam.camera_info_topic.value_or("")
                                                    : "";
  if (!(settings.idle_s > 0) || !(settings.lag_s >= 0) || !(settings.duration_s >= 0))
    throw InputError("--idle must be > 0, --lag and --duration >= 0");
  if (!net_.has_calibration(camera_index) && info_topic_.empty())
    throw InputError(sources::calibration_not_found(net_.name(), cam.id) +
                     "; network.yaml names no camera_info_topic for it");
  const bool compressed = ends_with(image_topic_, "/compressed");
  image_type_ = compressed ? ros::kCompressedImageType : ros::kImageType;
  images_ = std::make_unique<RosTopicReader>(
      domain, dds_topic_of(image_topic_),
      compressed ? ros::compressed_image_descriptor() : ros::image_descriptor(), false, false,
      security);
  if (!net_.has_calibration(camera_index))
    infos_ = std::make_unique<RosTopicReader>(
        domain, dds_topic_of(info_topic_), ros::camera_info_descriptor(), false, false, security);
}

LiveCamera::~LiveCamera() = default;

bool LiveCamera::take_images(double timeout_s) {
  const double give_up = epoch_seconds() + timeout_s;
  while (!net_.has_calibration(index_)) {  // the first camera info, before any image is used
    const double left = give_up - epoch_seconds();
    const auto infos = infos_->take(std::max(0.0, left));
    if (!infos.empty()) {
      net_.set_calibration(index_, ros::decode_camera_info(infos.front(), info_topic_));
      break;
    }
    if (left <= 0) return false;
  }
  auto msgs = images_->take(std::max(0.0, give_up - epoch_seconds()));
  if (msgs.empty()) return false;
  std::vector<std::pair<double, size_t>> order;
  for (size_t m = 0; m < msgs.size(); ++m) {
    std::string why;
    const auto ns = ros::header_stamp_ns(msgs[m].data(), msgs[m].size(), why);
    if (!ns)
      throw InputError(image_topic_ + ": message " + std::to_string(received_ + m) + ": " + why);
    order.emplace_back(static_cast<double>(*ns) * 1e-9, m);
  }
  std::stable_sort(order.begin(), order.end());
  for (const auto& [t, m] : order) {
    const std::string where = image_topic_ + ": message " + std::to_string(received_++);
    if (ended_) continue;
    if (last_stamp_ && t <= *last_stamp_) {
      ++out_of_order_;
      continue;
    }
    if (settings_.duration_s > 0 && first_stamp_ && t >= *first_stamp_ + settings_.duration_s) {
      ended_ = true;
      continue;
    }
    net_.append(index_, t, ros::decode_gray(image_type_, msgs[m], where), where);
    const double now = epoch_seconds();
    if (!first_stamp_) {
      first_stamp_ = t;
      first_wall_ = now;
    }
    last_stamp_ = t;
    last_wall_ = now;
  }
  return true;
}

bool LiveCamera::wait_frame(int frame, double first_timeout_s) {
  while (net_.camera_frame_count(index_) <= frame) {
    if (ended_) return false;
    if (!first_stamp_) {
      if (!take_images(first_timeout_s) && !first_stamp_) {
        // Images published and all lost to a full socket buffer look like none published.
        const std::uint64_t drops = udp_drops_of_this_process().value_or(0);
        throw InputError(
            image_topic_ + ": no image within " + io::format_number(first_timeout_s) + " s" +
            (net_.has_calibration(index_) ? "" : " (nor camera info on " + info_topic_ + ")") +
            (drops > 0 ? "; " + kernel_drops_consequence(drops) : ""));
      }
      continue;
    }
    // What came while this node was busy (integrating, or starved of the CPU) for longer than
    // idle_s is taken too: the stream is silent only when nothing is waiting and nothing comes
    // within what is left of idle_s.
    const double left = last_wall_ + settings_.idle_s - epoch_seconds();
    if (!take_images(std::max(0.0, left)))
      ended_ = ended_ || epoch_seconds() >= last_wall_ + settings_.idle_s;
  }
  return true;
}

}  // namespace netvmo::net
