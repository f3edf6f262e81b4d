#include "netvmo/pipeline/ros/image_msgs.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <dds/ddsrt/endian.h>

#include "SensorMsgs.h"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"
#include "ros_time.hpp"

namespace netvmo::ros {

namespace {

using Header = std_msgs_msg_dds__Header_;
using Image = sensor_msgs_msg_dds__Image_;
using Compressed = sensor_msgs_msg_dds__CompressedImage_;
using Info = sensor_msgs_msg_dds__CameraInfo_;

using detail::time_of;

// The number of distortion coefficients of a ROS distortion model, 0 when it is not read.
int coefficients(const std::string& model) {
  if (model == "plumb_bob") return 5;
  if (model == "rational_polynomial") return 8;
  if (model == "equidistant") return 4;
  return 0;
}

}  // namespace

const std::vector<std::string>& image_encodings() {
  static const std::vector<std::string> e{"mono8", "mono16", "rgb8",   "bgr8",
                                          "rgba8", "bgra8",  "yuv422", "yuv422_yuy2"};
  return e;
}

std::optional<std::int64_t> header_stamp_ns(const std::uint8_t* data, std::size_t size,
                                            std::string& why_not) {
  Decoded<Header> h(std_msgs_msg_dds__Header__desc);
  if (!h.read(data, size, why_not)) return std::nullopt;
  if (h->stamp.nanosec >= 1'000'000'000u) {
    why_not = "stamp.nanosec " + std::to_string(h->stamp.nanosec) + " is not below 10^9";
    return std::nullopt;
  }
  return std::int64_t{h->stamp.sec} * 1'000'000'000 + h->stamp.nanosec;
}

cv::Mat decode_gray(const std::string& type, const std::vector<std::uint8_t>& msg,
                    const std::string& where) {
  std::string why;
  if (type == kCompressedImageType) {
    Decoded<Compressed> c(sensor_msgs_msg_dds__CompressedImage__desc);
    if (!c.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
    const cv::Mat bytes(1, static_cast<int>(c->data._length), CV_8U, c->data._buffer);
    if (const std::string cut = io::image_cut_short(c->data._buffer, c->data._length); !cut.empty())
      throw InputError(where + ": data: " + cut);
    cv::Mat gray;
    try {
      if (c->data._length > 0) gray = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
      throw InputError(where + ": data: cannot be decoded as an image (format '" +
                       std::string(c->format ? c->format : "") + "'): " + e.err);
    }
    if (gray.empty())
      throw InputError(where + ": data: cannot be decoded as an image (format '" +
                       std::string(c->format ? c->format : "") + "')");
    return gray;
  }
  if (type != kImageType)
    throw InputError(where + ": type " + type + " is not an image (" + kImageType + " or " +
                     kCompressedImageType + ")");
  Decoded<Image> im(sensor_msgs_msg_dds__Image__desc);
  if (!im.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
  const std::string enc = im->encoding ? im->encoding : "";
  const auto& known = image_encodings();
  if (std::find(known.begin(), known.end(), enc) == known.end()) {
    std::string list;
    for (const auto& e : known) list += (list.empty() ? "" : ", ") + e;
    throw InputError(where + ": encoding: '" + enc + "' is not read (" + list + ")");
  }
  const int channels = enc == "mono8"                                ? 1
                       : enc == "mono16" || enc.rfind("yuv", 0) == 0 ? 2
                       : enc == "rgb8" || enc == "bgr8"              ? 3
                                                                     : 4;
  const uint64_t w = im->width, h = im->height, row = w * static_cast<uint64_t>(channels);
  if (w == 0 || h == 0 || w > 20000 || h > 20000)
    throw InputError(where + ": width, height: " + std::to_string(w) + "x" + std::to_string(h) +
                     " is not an image size (1 to 20000 pixels each way)");
  if (im->step < row)
    throw InputError(where + ": step: " + std::to_string(im->step) + " bytes is less than a row (" +
                     std::to_string(row) + " for " + std::to_string(w) + " pixels of " + enc + ")");
  if (static_cast<uint64_t>(im->data._length) < im->step * h)
    throw InputError(where + ": data: " + std::to_string(im->data._length) + " bytes, step x " +
                     "height needs " + std::to_string(im->step * h));
  if (enc == "mono16" && im->step % 2 != 0)
    throw InputError(where + ": step: " + std::to_string(im->step) +
                     " bytes is not a whole number of 16-bit pixels");
  const int type_cv = channels == 1     ? CV_8UC1
                      : enc == "mono16" ? CV_16UC1
                      : channels == 2   ? CV_8UC2
                      : channels == 3   ? CV_8UC3
                                        : CV_8UC4;
  const cv::Mat view(static_cast<int>(h), static_cast<int>(w), type_cv, im->data._buffer, im->step);
  cv::Mat gray;
  if (enc == "mono8") {
    gray = view.clone();
  } else if (enc == "mono16") {
    cv::Mat m = view.clone();
    const bool big = im->is_bigendian != 0;
    if (big != (DDSRT_ENDIAN == DDSRT_BIG_ENDIAN))
      for (int r = 0; r < m.rows; ++r) {
        auto* p = m.ptr<uint16_t>(r);
        for (int c = 0; c < m.cols; ++c) p[c] = static_cast<uint16_t>((p[c] >> 8) | (p[c] << 8));
      }
    m.convertTo(gray, CV_8U, 1.0 / 257.0);
  } else if (enc == "rgb8") {
    cv::cvtColor(view, gray, cv::COLOR_RGB2GRAY);
  } else if (enc == "bgr8") {
    cv::cvtColor(view, gray, cv::COLOR_BGR2GRAY);
  } else if (enc == "rgba8") {
    cv::cvtColor(view, gray, cv::COLOR_RGBA2GRAY);
  } else if (enc == "bgra8") {
    cv::cvtColor(view, gray, cv::COLOR_BGRA2GRAY);
  } else if (enc == "yuv422") {
    cv::cvtColor(view, gray, cv::COLOR_YUV2GRAY_UYVY);
  } else {
    cv::cvtColor(view, gray, cv::COLOR_YUV2GRAY_YUY2);
  }
  return gray;
}

io::Calibration decode_camera_info(const std::vector<std::uint8_t>& msg, const std::string& where) {
  std::string why;
  Decoded<Info> ci(sensor_msgs_msg_dds__CameraInfo__desc);
  if (!ci.read(msg.data(), msg.size(), why)) throw InputError(where + ": " + why);
  io::Calibration c;
  c.source = where;
  c.width = static_cast<int>(std::min<uint32_t>(ci->width, 1u << 30));
  c.height = static_cast<int>(std::min<uint32_t>(ci->height, 1u << 30));
  c.K = cv::Matx33d(ci->k);
  const std::string model = ci->distortion_model ? ci->distortion_model : "";
  const int n = coefficients(model);
  if (n == 0)
    throw InputError(where + ": distortion_model: '" + model +
                     "' is not supported (supported: plumb_bob, rational_polynomial, "
                     "equidistant)");
  if (ci->d._length != static_cast<uint32_t>(n))
    throw InputError(where + ": d: distortion_model " + model + " takes " + std::to_string(n) +
                     " coefficients, the message has " + std::to_string(ci->d._length));
  c.fisheye = n == 4;
  for (int i = 0; i < std::min(n, 5); ++i) c.dist[i] = ci->d._buffer[i];
  for (int i = 5; i < n; ++i) c.rational[i - 5] = ci->d._buffer[i];
  bool identity = true, zero = true;
  for (int i = 0; i < 9; ++i) {
    identity = identity && ci->r[i] == (i % 4 == 0 ? 1.0 : 0.0);
    zero = zero && ci->r[i] == 0.0;
  }
  if (!identity && !zero)
    throw InputError(where +
                     ": r: not the identity (a stereo camera's rectification); netvmo uses raw "
                     "images with k and d, which a monocular camera_info describes");
  if (c.width <= 0 || c.height <= 0 || c.width > 20000 || c.height > 20000)
    throw InputError(where + ": width, height: " + std::to_string(ci->width) + "x" +
                     std::to_string(ci->height) + " is not an image size (1 to 20000 each way)");
  if (!(c.K(0, 0) > 0) || !(c.K(1, 1) > 0) || c.K(1, 0) != 0 || c.K(2, 0) != 0 || c.K(2, 1) != 0 ||
      c.K(2, 2) != 1 || !std::isfinite(c.K(0, 2)) || !std::isfinite(c.K(1, 2)))
    throw InputError(where + ": k: expected [fx s cx; 0 fy cy; 0 0 1] with fx, fy > 0");
  for (uint32_t i = 0; i < ci->d._length; ++i)
    if (!std::isfinite(ci->d._buffer[i])) throw InputError(where + ": d: not finite");
  return c;
}

void with_image(const cv::Mat& gray, const std::string& encoding, std::int64_t stamp_ns,
                const std::string& frame_id, const std::function<void(const void*)>& use) {
  CV_Assert(gray.type() == CV_8UC1 && (encoding == "mono8" || encoding == "rgb8"));
  cv::Mat pixels = gray;
  if (encoding == "rgb8") cv::cvtColor(gray, pixels, cv::COLOR_GRAY2RGB);
  pixels = pixels.isContinuous() ? pixels : pixels.clone();
  Image m{};
  m.header.stamp = time_of(stamp_ns);
  m.header.frame_id = const_cast<char*>(frame_id.c_str());
  m.height = static_cast<uint32_t>(pixels.rows);
  m.width = static_cast<uint32_t>(pixels.cols);
  m.encoding = const_cast<char*>(encoding.c_str());
  m.is_bigendian = 0;
  m.step = static_cast<uint32_t>(pixels.cols * pixels.channels());
  m.data._length = m.data._maximum = static_cast<uint32_t>(pixels.total() * pixels.elemSize());
  m.data._buffer = pixels.data;
  m.data._release = false;
  use(&m);
}

std::vector<std::uint8_t> encode_image(const cv::Mat& gray, const std::string& encoding,
                                       std::int64_t stamp_ns, const std::string& frame_id) {
  std::vector<std::uint8_t> out;
  with_image(gray, encoding, stamp_ns, frame_id,
             [&](const void* m) { out = encode(sensor_msgs_msg_dds__Image__desc, m); });
  return out;
}

void with_compressed_image(const cv::Mat& image, const std::string& format, std::int64_t stamp_ns,
                           const std::string& frame_id, int quality,
                           const std::function<void(const void*)>& use) {
  std::vector<uchar> bytes;
  CV_Assert(format == "png" || format == "jpeg");
  CV_Assert(image.type() == CV_8UC1 || image.type() == CV_8UC3);
  if (format == "png")
    cv::imencode(".png", image, bytes);
  else
    cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  Compressed m{};
  m.header.stamp = time_of(stamp_ns);
  m.header.frame_id = const_cast<char*>(frame_id.c_str());
  m.format = const_cast<char*>(format.c_str());
  m.data._length = m.data._maximum = static_cast<uint32_t>(bytes.size());
  m.data._buffer = bytes.data();
  m.data._release = false;
  use(&m);
}

std::vector<std::uint8_t> encode_compressed_image(const cv::Mat& image, const std::string& format,
                                                  std::int64_t stamp_ns,
                                                  const std::string& frame_id, int quality) {
  std::vector<std::uint8_t> out;
  with_compressed_image(image, format, stamp_ns, frame_id, quality, [&](const void* m) {
    out = encode(sensor_msgs_msg_dds__CompressedImage__desc, m);
  });
  return out;
}

void with_camera_info(const io::Calibration& c, std::int64_t stamp_ns, const std::string& frame_id,
                      const std::function<void(const void*)>& use) {
  Info m{};
  m.header.stamp = time_of(stamp_ns);
  m.header.frame_id = const_cast<char*>(frame_id.c_str());
  m.height = static_cast<uint32_t>(c.height);
  m.width = static_cast<uint32_t>(c.width);
  std::vector<double> d;
  std::string model;
  if (c.fisheye) {
    model = "equidistant";
    d = {c.dist[0], c.dist[1], c.dist[2], c.dist[3]};
  } else if (c.is_rational()) {
    model = "rational_polynomial";
    d = {c.dist[0], c.dist[1],     c.dist[2],     c.dist[3],
         c.dist[4], c.rational[0], c.rational[1], c.rational[2]};
  } else {
    model = "plumb_bob";
    d = {c.dist[0], c.dist[1], c.dist[2], c.dist[3], c.dist[4]};
  }
  m.distortion_model = const_cast<char*>(model.c_str());
  m.d._length = m.d._maximum = static_cast<uint32_t>(d.size());
  m.d._buffer = d.data();
  m.d._release = false;
  for (int i = 0; i < 9; ++i) m.k[i] = c.K.val[i];
  for (int i = 0; i < 9; ++i) m.r[i] = i % 4 == 0 ? 1.0 : 0.0;
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col) m.p[r * 4 + col] = c.K(r, col);
  m.binning_x = m.binning_y = 0;
  use(&m);
}

std::vector<std::uint8_t> encode_camera_info(const io::Calibration& c, std::int64_t stamp_ns,
                                             const std::string& frame_id) {
  std::vector<std::uint8_t> out;
  with_camera_info(c, stamp_ns, frame_id,
                   [&](const void* m) { out = encode(sensor_msgs_msg_dds__CameraInfo__desc, m); });
  return out;
}

const dds_topic_descriptor_t& image_descriptor() {
  return sensor_msgs_msg_dds__Image__desc;
}
const dds_topic_descriptor_t& compressed_image_descriptor() {
  return sensor_msgs_msg_dds__CompressedImage__desc;
}
const dds_topic_descriptor_t& camera_info_descriptor() {
  return sensor_msgs_msg_dds__CameraInfo__desc;
}

}  // namespace netvmo::ros
