#include "netvmo/pipeline/sources/bag_export.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <tuple>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/ros/pose_msgs.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;

int write_bag(Dataset& ds, const fs::path& out, const BagExportSettings& s) {
  const bool raw = s.encoding == "mono8" || s.encoding == "rgb8";
  if (!raw && s.encoding != "png" && s.encoding != "jpeg")
    throw InputError("bag encoding '" + s.encoding + "' is not one of mono8, rgb8, png, jpeg");
  ros::RosBagWriter bag(out);
  io::NetworkConfig net = ds.network;
  std::vector<int> image_topic(ds.cameras.size()), info_topic(ds.cameras.size(), 0);
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const std::string base = "/cam_" + std::to_string(ds.cameras[i].id);
    net.cameras[i].image_topic = base + (raw ? "/image_raw" : "/image_raw/compressed");
    image_topic[i] = bag.add_topic(*net.cameras[i].image_topic,
                                   raw ? ros::kImageType : ros::kCompressedImageType);
    if (s.camera_info) {
      net.cameras[i].camera_info_topic = base + "/camera_info";
      info_topic[i] = bag.add_topic(*net.cameras[i].camera_info_topic, ros::kCameraInfoType);
    } else {
      net.cameras[i].camera_info_topic.reset();
    }
  }
  // Every image, in time order (camera order for equal times).
  std::vector<std::tuple<double, size_t, int>> images;
  for (size_t i = 0; i < ds.cameras.size(); ++i)
    for (int f = 0; f < std::min(ds.camera_frame_count(i), ds.cameras[i].source->frame_count());
         ++f)
      if (ds.cameras[i].source->has_frame(f)) images.emplace_back(ds.frame_time(i, f), i, f);
  std::sort(images.begin(), images.end());
  std::vector<bool> info_written(ds.cameras.size(), false);
  for (const auto& [t, i, f] : images) {
    const std::int64_t ns = s.stamp_origin_ns + std::llround(t * 1e9);
    const std::string frame_id = ros::camera_frame(ds.cameras[i].id);
    if (s.camera_info && !info_written[i]) {
      bag.write(info_topic[i], ns, ros::encode_camera_info(ds.cameras[i].calib, ns, frame_id));
      info_written[i] = true;
    }
    const cv::Mat gray = ds.read(i, f);
    bag.write(image_topic[i], ns,
              raw ? ros::encode_image(gray, s.encoding, ns, frame_id)
                  : ros::encode_compressed_image(gray, s.encoding, ns, frame_id));
  }
  bag.close();
  {
    std::ofstream y(out / "network.yaml");
    y << io::network_yaml(net);
    if (!y) throw InputError((out / "network.yaml").string() + ": cannot be written");
  }
  for (const char* f : {"truth.csv", "target.csv", "cameras.csv", "truth_cameras.csv"})
    if (fs::exists(ds.dir / f)) fs::copy_file(ds.dir / f, out / f);
  if (!s.camera_info && fs::is_directory(ds.dir / "calib"))
    fs::copy(ds.dir / "calib", out / "calib", fs::copy_options::recursive);
  return static_cast<int>(images.size());
}

}  // namespace netvmo::sources
