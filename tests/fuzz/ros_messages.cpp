// Fuzz target: the ROS 2 messages of a rosbag2 bag's camera topics, from a .db3 row's bytes
// (ros/image_msgs.hpp): header.stamp, then the bytes read as sensor_msgs Image, CompressedImage
// and CameraInfo, each through Cyclone DDS's CDR normalize and read (ros/cdr.hpp). A message
// must give an image or an InputError; an accepted calibration must be usable.
#include <cstdint>
#include <vector>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> msg(data, data + size);
  std::string why;
  (void)ros::header_stamp_ns(msg.data(), msg.size(), why);
  for (const char* type : {ros::kImageType, ros::kCompressedImageType}) {
    try {
      const cv::Mat g = ros::decode_gray(type, msg, "fuzz");
      if (g.empty() || g.type() != CV_8UC1) __builtin_trap();
    } catch (const InputError&) {
    }
  }
  try {
    const io::Calibration c = ros::decode_camera_info(msg, "fuzz");
    const std::vector<cv::Point2d> px = {{0, 0}, {c.width - 1.0, c.height - 1.0}};
    (void)io::normalize_points(px, c);
  } catch (const InputError&) {
  }
  return 0;
}
