// ROS 2 camera messages <-> images and calibrations: sensor_msgs/msg/Image (raw pixels with an
// encoding), sensor_msgs/msg/CompressedImage (JPEG or PNG bytes) and sensor_msgs/msg/CameraInfo,
// as serialized in a bag (cdr.hpp).
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::ros {

inline constexpr const char* kImageType = "sensor_msgs/msg/Image";
inline constexpr const char* kCompressedImageType = "sensor_msgs/msg/CompressedImage";
inline constexpr const char* kCameraInfoType = "sensor_msgs/msg/CameraInfo";

/// The encodings of sensor_msgs/msg/Image that are read: mono8, mono16, rgb8, bgr8, rgba8,
/// bgra8, yuv422 (UYVY, as ROS names it) and yuv422_yuy2 (YUYV), big- or little-endian for
/// mono16.
const std::vector<std::string>& image_encodings();

/// header.stamp [ns since the epoch] of a serialized message whose first field is a
/// std_msgs/msg/Header (every type above); the first bytes of it are enough. Returns nullopt,
/// with why_not, when they are not a header.
std::optional<std::int64_t> header_stamp_ns(const std::uint8_t* data, std::size_t size,
                                            std::string& why_not);

/// The 8-bit gray image of a serialized Image (`type` kImageType) or CompressedImage
/// (kCompressedImageType). Throws InputError(where + ": ...") for a malformed message, an
/// encoding not in image_encodings(), a step or data size that does not match height x width,
/// or compressed bytes OpenCV cannot decode.
cv::Mat decode_gray(const std::string& type, const std::vector<std::uint8_t>& msg,
                    const std::string& where);

/// The intrinsics of a serialized CameraInfo: width and height, k, and distortion_model with d
/// (plumb_bob: 5 coefficients, rational_polynomial: 8, equidistant: 4), r the identity (a
/// monocular camera's). Throws InputError(where + ": <field>: ...").
io::Calibration decode_camera_info(const std::vector<std::uint8_t>& msg, const std::string& where);

/// Serialized messages for a bag (ROS 2's CDR_LE). `gray` is 8-bit single-channel; `encoding`
/// mono8 or rgb8 (the gray value in each channel); `format` "png" or "jpeg".
std::vector<std::uint8_t> encode_image(const cv::Mat& gray, const std::string& encoding,
                                       std::int64_t stamp_ns, const std::string& frame_id);
/// `image` may also be 8-bit BGR (an overlay); `quality` is JPEG's (OpenCV's default 95).
std::vector<std::uint8_t> encode_compressed_image(const cv::Mat& image, const std::string& format,
                                                  std::int64_t stamp_ns,
                                                  const std::string& frame_id, int quality = 95);
std::vector<std::uint8_t> encode_camera_info(const io::Calibration& calib, std::int64_t stamp_ns,
                                             const std::string& frame_id);

/// The same messages as idlc structs, valid during the call to `use` only: for dds_write
/// (net::play).
void with_image(const cv::Mat& gray, const std::string& encoding, std::int64_t stamp_ns,
                const std::string& frame_id, const std::function<void(const void*)>& use);
void with_compressed_image(const cv::Mat& image, const std::string& format, std::int64_t stamp_ns,
                           const std::string& frame_id, int quality,
                           const std::function<void(const void*)>& use);
void with_camera_info(const io::Calibration& calib, std::int64_t stamp_ns,
                      const std::string& frame_id, const std::function<void(const void*)>& use);
/// The idlc descriptors, for topics of these types.
const dds_topic_descriptor_t& image_descriptor();
const dds_topic_descriptor_t& compressed_image_descriptor();
const dds_topic_descriptor_t& camera_info_descriptor();

}  // namespace netvmo::ros
