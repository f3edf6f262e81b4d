#include "netvmo/pipeline/sources/topic_network.hpp"

#include <algorithm>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;

TopicNetwork::TopicNetwork(const fs::path& dir, std::optional<int> only_camera) : dir_(dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": dataset folder not found");
  net_ = io::load_network_config(dir / "network.yaml");
  const size_t n = net_.cameras.size();
  calib_.resize(n);
  times_.resize(n);
  images_.resize(n);
  for (size_t i = 0; i < n; ++i)
    if (!only_camera || net_.cameras[i].id == *only_camera)
      calib_[i] = find_calibration(dir, net_.cameras[i].id);
}

const io::Calibration& TopicNetwork::calibration(size_t i) const {
  if (!calib_.at(i))
    throw InputError(calibration_not_found(dir_, net_.cameras[i].id) +
                     " and no camera info received");
  return *calib_[i];
}

void TopicNetwork::set_calibration(size_t i, io::Calibration calib) {
  calib_.at(i) = std::move(calib);
}

std::string TopicNetwork::image_topic(size_t i) const {
  const auto& t = net_.cameras.at(i).image_topic;
  if (!t)
    throw InputError(net_.source + ": cameras[" + std::to_string(i) +
                     "].image_topic: missing (a live camera names its ROS 2 image topic)");
  return *t;
}

void TopicNetwork::append(size_t i, double t, cv::Mat image, const std::string& where) {
  const io::Calibration& c = calibration(i);
  if (image.cols != c.width || image.rows != c.height)
    throw InputError(where + ": image is " + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + " but " + c.source + " says " +
                     std::to_string(c.width) + "x" + std::to_string(c.height));
  times_.at(i).push_back(t);
  images_.at(i).push_back(std::move(image));
}

int TopicNetwork::frame_count() const {
  size_t most = 0;
  for (const auto& t : times_) most = std::max(most, t.size());
  return static_cast<int>(most);
}

int TopicNetwork::camera_frame_count(size_t i) const {
  return static_cast<int>(times_.at(i).size());
}

std::optional<double> TopicNetwork::listed_time(size_t i, int frame) const {
  const auto& t = times_.at(i);
  if (frame < 0 || static_cast<size_t>(frame) >= t.size()) return std::nullopt;
  return t[static_cast<size_t>(frame)];
}

cv::Mat TopicNetwork::read(size_t i, int frame) {
  auto& im = images_.at(i);
  if (frame < 0 || static_cast<size_t>(frame) >= im.size()) return {};
  cv::Mat out;
  std::swap(out, im[static_cast<size_t>(frame)]);
  return out;
}

bool is_topic_network(const fs::path& dir) {
  if (ros::RosBag::is_bag(dir) || !fs::exists(dir / "network.yaml")) return false;
  const auto net = io::load_network_config(dir / "network.yaml");
  return std::any_of(net.cameras.begin(), net.cameras.end(),
                     [](const io::CameraConfig& c) { return c.image_topic.has_value(); });
}

}  // namespace netvmo::sources
