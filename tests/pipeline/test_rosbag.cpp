// rosbag2 bags as datasets (ros/rosbag.hpp, sources/bag_export.hpp): a dataset written as a bag
// reads back as the same images, times and calibrations, `netvmo run` on it equals `run` on the
// folder, every image encoding decodes to the gray the pixels say, the CDR is ROS 2's byte for
// byte, and a bad bag is one line naming the file and what is wrong.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "SensorMsgs.h"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/ros/pose_msgs.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"
#include "netvmo/pipeline/sources/bag_export.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using test::expect_input_error;

fs::path synth_folder(const fs::path& dir, int cameras, int frames) {
  testing::SynthDatasetSpec spec = testing::simple_dataset_spec(cameras, frames);
  spec.cameras[1].calib = testing::test_calibration(true);  // one camera with distortion
  testing::write_synth_dataset(dir, spec);
  return dir;
}

// Every image, time and calibration of the bag is the folder's (lossless encodings), or within
// JPEG's error.
void expect_same_dataset(const fs::path& folder, const fs::path& bag, double max_mean_diff) {
  sources::Dataset a = sources::open_dataset(folder), b = sources::open_dataset(bag);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  EXPECT_EQ(a.frame_count, b.frame_count);
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    EXPECT_EQ(a.cameras[i].calib.K, b.cameras[i].calib.K) << "camera " << i;
    EXPECT_EQ(a.cameras[i].calib.dist, b.cameras[i].calib.dist) << "camera " << i;
    EXPECT_EQ(a.cameras[i].calib.width, b.cameras[i].calib.width);
    for (int f = 0; f < a.frame_count; ++f) {
      EXPECT_EQ(a.frame_time(i, f), b.frame_time(i, f)) << "camera " << i << " frame " << f;
      const cv::Mat x = a.read(i, f), y = b.read(i, f);
      ASSERT_EQ(x.size(), y.size());
      cv::Mat d;
      cv::absdiff(x, y, d);
      EXPECT_LE(cv::mean(d)[0], max_mean_diff) << "camera " << i << " frame " << f;
    }
  }
}

TEST(RosBag, EveryEncodingReadsBackAsTheFolder) {
  const fs::path dir = test::scratch_dir("rosbag_same");
  const fs::path folder = synth_folder(dir / "ds", 3, 6);
  sources::Dataset ds = sources::open_dataset(folder);
  for (const std::string enc : {"mono8", "rgb8", "png"}) {
    sources::BagExportSettings s;
    s.encoding = enc;
    EXPECT_EQ(sources::write_bag(ds, dir / enc, s), 18);
    SCOPED_TRACE(enc);
    expect_same_dataset(folder, dir / enc, 0.0);
  }
  sources::BagExportSettings jpeg;
  jpeg.encoding = "jpeg";
  sources::write_bag(ds, dir / "jpeg", jpeg);
  expect_same_dataset(folder, dir / "jpeg", 3.0);
  // calib/ copied instead of CameraInfo topics.
  sources::BagExportSettings no_info;
  no_info.camera_info = false;
  sources::write_bag(ds, dir / "calib", no_info);
  EXPECT_TRUE(fs::exists(dir / "calib" / "calib" / "cam_1.yaml"));
  EXPECT_EQ(ros::RosBag(dir / "calib").topics().size(), 3u);
  expect_same_dataset(folder, dir / "calib", 0.0);
  fs::remove_all(dir);
}

// The netvmo command on a bag: `bag` writes it, `run` on it writes the folder's estimates, byte
// for byte, and `detect` and `sweep` the folder's detections.csv and sweep.csv (launch on a bag:
// Launch.ABagLaunchesAsItsFolderRuns).
TEST(RosBag, RunOnTheBagEqualsRunOnTheFolder) {
  const fs::path dir = test::scratch_dir("rosbag_run");
  synth_folder(dir / "ds", 3, 8);
  const auto bag = test::run_netvmo(
      "bag " + (dir / "ds").string() + " --out " + (dir / "bag").string() + " --encoding png", dir,
      300);
  ASSERT_EQ(bag.code, 0) << bag.err;
  EXPECT_TRUE(fs::exists(dir / "bag" / "metadata.yaml"));
  for (const char* what : {"ds", "bag"}) {
    const auto r = test::run_netvmo("run " + (dir / what).string() + " --out " +
                                        (dir / (std::string("out_") + what)).string() +
                                        " --no-plots --no-overlays",
                                    dir, 300);
    ASSERT_EQ(r.code, 0) << what << ": " << r.err;
  }
  for (const char* f : {"estimates.csv", "errors.csv", "energies.csv"}) {
    EXPECT_EQ(test::slurp(dir / "out_ds" / f), test::slurp(dir / "out_bag" / f)) << f;
    EXPECT_FALSE(test::slurp(dir / "out_bag" / f).empty()) << f;
  }
  // detect and sweep too.
  for (const char* what : {"ds", "bag"}) {
    const std::string in = (dir / what).string(), tag = std::string("_") + what;
    const auto d =
        test::run_netvmo("detect " + in + " --out " + (dir / ("det" + tag)).string(), dir, 300);
    ASSERT_EQ(d.code, 0) << what << ": " << d.err;
    const auto s = test::run_netvmo(
        "sweep " + in + " --out " + (dir / ("sweep" + tag)).string() + " --ks 2,20", dir, 300);
    ASSERT_EQ(s.code, 0) << what << ": " << s.err;
  }
  EXPECT_EQ(test::slurp(dir / "det_ds" / "detections.csv"),
            test::slurp(dir / "det_bag" / "detections.csv"));
  EXPECT_EQ(test::slurp(dir / "sweep_ds" / "sweep.csv"),
            test::slurp(dir / "sweep_bag" / "sweep.csv"));
  fs::remove_all(dir);
}

// `run --bag`: the run as a bag, each camera's overlay and camera info every frame, its
// measurement (the PnP pose with a covariance) in every frame it detects the target, its
// estimate every frame it has one (equal to estimates.csv), the rig on /tf_static and the
// estimates on /tf; a --bag folder that is not netvmo's is refused in one line, nothing written.
TEST(RosBag, RunWritesTheRunAsABag) {
  const fs::path dir = test::scratch_dir("rosbag_run_bag");
  const int frames = 6;
  synth_folder(dir / "ds", 3, frames);
  const auto r =
      test::run_netvmo("run " + (dir / "ds").string() + " --out " + (dir / "out").string() +
                           " --bag " + (dir / "bag").string() + " --no-plots --no-overlays",
                       dir, 300);
  ASSERT_EQ(r.code, 0) << r.err;
  const sources::Dataset ds = sources::open_dataset(dir / "ds");
  const ros::RosBag bag(dir / "bag");
  // estimates.csv: frame,t,camera,delta,px,py,pz,rx,ry,rz
  std::map<std::pair<int, int>, std::vector<double>> rows;  // (frame, camera id) -> row
  {
    std::istringstream in(test::slurp(dir / "out" / "estimates.csv"));
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::vector<double> v;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) v.push_back(std::stod(c));
      ASSERT_EQ(v.size(), 10u) << line;
      rows[{static_cast<int>(v[0]), static_cast<int>(v[2])}] = v;
    }
  }
  const auto frame_of = [&](std::int64_t ns) {
    return static_cast<int>(std::llround(ns * 1e-9 * ds.network.fps));
  };
  for (const auto& cam : ds.network.cameras) {
    const std::string p = "/netvmo/camera_" + std::to_string(cam.id);
    SCOPED_TRACE(p);
    for (const char* t : {"/overlay/compressed", "/camera_info"}) {
      const auto* topic = bag.find_topic(p + t);
      ASSERT_NE(topic, nullptr) << t;
      EXPECT_EQ(topic->message_count, static_cast<std::uint64_t>(frames)) << t;
    }
    const auto overlays = bag.messages(p + "/overlay/compressed");
    const cv::Mat first = ros::decode_gray(ros::kCompressedImageType, bag.read(overlays.at(0)),
                                           bag.where(overlays.at(0)));
    EXPECT_EQ(first.cols, 640);  // the synthetic cameras' images, at full resolution
    EXPECT_EQ(first.rows, 480);
    int estimates = 0, detections = 0, measurements = 0;
    for (const auto& m : bag.messages(p + "/average_pose_with_covariance")) {
      const auto pose = ros::decode_pose_with_covariance(bag.read(m), bag.where(m));
      EXPECT_EQ(pose.frame_id, "world");
      const auto it = rows.find({frame_of(pose.stamp_ns), cam.id});
      ASSERT_NE(it, rows.end());
      const auto& v = it->second;
      const obs::SE3 est = obs::make_pose(obs::Vec3(v[4], v[5], v[6]), obs::Vec3(v[7], v[8], v[9]));
      EXPECT_LT((pose.pose.matrix() - est.matrix()).cwiseAbs().maxCoeff(), 1e-8);
      ASSERT_TRUE(pose.covariance.has_value());  // every camera has an initialised neighbour
      EXPECT_LT((*pose.covariance - pose.covariance->transpose()).cwiseAbs().maxCoeff(), 1e-15);
      ++estimates;
    }
    EXPECT_EQ(bag.find_topic(p + "/average_pose")->message_count,
              static_cast<std::uint64_t>(estimates));
    for (const auto& [key, v] : rows)
      if (key.second == cam.id) detections += v[3] == 1.0;
    for (const auto& m : bag.messages(p + "/measurement")) {
      const auto pose = ros::decode_pose_with_covariance(bag.read(m), bag.where(m));
      EXPECT_EQ(pose.frame_id, "cam_" + std::to_string(cam.id));
      EXPECT_EQ(rows.at({frame_of(pose.stamp_ns), cam.id})[3], 1.0);
      ASSERT_TRUE(pose.covariance.has_value());
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(*pose.covariance);
      EXPECT_GT(eig.eigenvalues()(0), 0.0);
      // The tag 2 m in front of the camera.
      EXPECT_NEAR(pose.pose.translation().z(), 2.0, 0.05);
      ++measurements;
    }
    EXPECT_EQ(measurements, detections);
    EXPECT_GT(estimates, 0);
  }
  const auto statics = bag.messages("/tf_static");
  ASSERT_EQ(statics.size(), 1u);
  const auto rig = ros::decode_tf_message(bag.read(statics[0]), "tf_static");
  ASSERT_EQ(rig.size(), ds.network.cameras.size());
  for (size_t i = 0; i < rig.size(); ++i) {
    EXPECT_EQ(rig[i].child, "cam_" + std::to_string(ds.network.cameras[i].id));
    EXPECT_LT((rig[i].pose.matrix() - ds.network.cameras[i].g_wi.matrix()).cwiseAbs().maxCoeff(),
              1e-12);
  }
  EXPECT_EQ(bag.find_topic("/tf")->message_count, static_cast<std::uint64_t>(frames));

  // A --bag folder that is not a netvmo output: one line naming it, nothing written.
  fs::create_directories(dir / "mine");
  test::write_text(dir / "mine" / "notes.txt", "keep me\n");
  const auto bad =
      test::run_netvmo("run " + (dir / "ds").string() + " --out " + (dir / "out2").string() +
                           " --bag " + (dir / "mine").string() + " --no-plots --no-overlays",
                       dir, 300);
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find((dir / "mine").string()), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_EQ(test::slurp(dir / "mine" / "notes.txt"), "keep me\n");
  EXPECT_FALSE(fs::exists(dir / "out2"));
  fs::remove_all(dir);
}

// An Image message of `encoding` with these pixel bytes.
std::vector<std::uint8_t> image_message(const std::string& encoding, int w, int h, int step,
                                        std::vector<std::uint8_t> bytes, bool big_endian = false) {
  sensor_msgs_msg_dds__Image_ m{};
  std::string frame = "cam";
  m.header.frame_id = frame.data();
  m.width = static_cast<uint32_t>(w);
  m.height = static_cast<uint32_t>(h);
  m.encoding = const_cast<char*>(encoding.c_str());
  m.is_bigendian = big_endian;
  m.step = static_cast<uint32_t>(step);
  m.data._length = m.data._maximum = static_cast<uint32_t>(bytes.size());
  m.data._buffer = bytes.data();
  return ros::encode(sensor_msgs_msg_dds__Image__desc, &m);
}

// A CompressedImage message whose JPEG or PNG data is cut short (a message truncated on its way)
// is refused naming the message (not decoded with the rest of the image gray, nor failing with
// the decoder's own line); the whole message decodes.
TEST(RosBag, CompressedImageCutShortIsRefused) {
  cv::Mat m(48, 64, CV_8UC1);
  cv::randu(m, 0, 256);
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", m, jpeg));
  const auto message = [](std::vector<uchar> data) {
    sensor_msgs_msg_dds__CompressedImage_ c{};
    std::string frame = "cam", format = "jpeg";
    c.header.frame_id = frame.data();
    c.format = format.data();
    c.data._length = c.data._maximum = static_cast<uint32_t>(data.size());
    c.data._buffer = data.data();
    return ros::encode(sensor_msgs_msg_dds__CompressedImage__desc, &c);
  };
  EXPECT_EQ(ros::decode_gray(ros::kCompressedImageType, message(jpeg), "m").size(), m.size());
  jpeg.resize(jpeg.size() * 2 / 3);
  expect_input_error(
      [&] { ros::decode_gray(ros::kCompressedImageType, message(jpeg), "topic message 7"); },
      {"topic message 7", "data: JPEG cut short"});
  std::vector<uchar> png;
  ASSERT_TRUE(cv::imencode(".png", m, png));
  EXPECT_EQ(ros::decode_gray(ros::kCompressedImageType, message(png), "m").size(), m.size());
  png.resize(png.size() * 2 / 3);
  expect_input_error(
      [&] { ros::decode_gray(ros::kCompressedImageType, message(png), "topic message 8"); },
      {"topic message 8", "data: PNG cut short"});
}

// Each encoding of a 2x1 image: the gray OpenCV's conversions give for the pixels (ITU-R BT.601
// luma, 0.299 R + 0.587 G + 0.114 B), Y itself for YUV 4:2:2, the high byte for 16 bits.
TEST(RosBag, ImageEncodingsDecodeToTheirGray) {
  const auto gray = [](const std::string& enc, int w, int step, std::vector<std::uint8_t> b,
                       bool big = false) {
    const cv::Mat g =
        ros::decode_gray(ros::kImageType, image_message(enc, w, 1, step, b, big), "m");
    EXPECT_EQ(g.type(), CV_8UC1) << enc;
    std::vector<int> v;
    for (int c = 0; c < g.cols; ++c) v.push_back(g.at<uchar>(0, c));
    return v;
  };
  EXPECT_EQ(gray("mono8", 2, 4, {10, 200, 0, 0}), (std::vector<int>{10, 200}));  // step > width
  // 16 bits: 0x1234 and 0xff00; 8 bits = v / 257 rounded.
  EXPECT_EQ(gray("mono16", 2, 4, {0x34, 0x12, 0x00, 0xff}), (std::vector<int>{18, 254}));
  EXPECT_EQ(gray("mono16", 2, 4, {0x12, 0x34, 0xff, 0x00}, true), (std::vector<int>{18, 254}));
  const int red = static_cast<int>(std::lround(0.299 * 255)),
            blue = static_cast<int>(std::lround(0.114 * 255));
  EXPECT_EQ(gray("rgb8", 2, 6, {255, 0, 0, 0, 0, 255}), (std::vector<int>{red, blue}));
  EXPECT_EQ(gray("bgr8", 2, 6, {255, 0, 0, 0, 0, 255}), (std::vector<int>{blue, red}));
  EXPECT_EQ(gray("rgba8", 2, 8, {255, 0, 0, 9, 0, 0, 255, 9}), (std::vector<int>{red, blue}));
  EXPECT_EQ(gray("bgra8", 2, 8, {255, 0, 0, 9, 0, 0, 255, 9}), (std::vector<int>{blue, red}));
  EXPECT_EQ(gray("yuv422", 2, 4, {128, 40, 128, 220}), (std::vector<int>{40, 220}));  // UYVY
  EXPECT_EQ(gray("yuv422_yuy2", 2, 4, {40, 128, 220, 128}), (std::vector<int>{40, 220}));
  expect_input_error(
      [&] {
        gray("bayer_rggb8", 2, 2, {1, 2});
      },
      {"m: encoding: 'bayer_rggb8' is not read", "mono8"});
  expect_input_error([&] { gray("mono8", 2, 1, {1, 2}); }, {"m: step: 1 bytes is less than a row"});
  expect_input_error([&] { gray("rgb8", 2, 6, {1, 2, 3}); }, {"m: data: 3 bytes"});
  // An odd step of 16-bit pixels (found by the fuzz target ros_messages: OpenCV threw from
  // cv::Mat's constructor, outside any InputError).
  expect_input_error(
      [&] {
        gray("mono16", 2, 5, {1, 2, 3, 4, 5});
      },
      {"m: step: 5 bytes is not a whole number of 16-bit pixels"});
}

// The bytes are ROS 2's CDR: a std_msgs/Header {stamp {sec 1, nanosec 2}, frame_id "ab"} is the
// CDR_LE encapsulation, two little-endian 32-bit words, then the string's length with its NUL
// and its bytes, as rmw_cyclonedds and rosbag2 write it; and what decode() reads back.
TEST(RosBag, CdrIsRos2sByteForByte) {
  std_msgs_msg_dds__Header_ h{};
  std::string id = "ab";
  h.stamp.sec = 1;
  h.stamp.nanosec = 2;
  h.frame_id = id.data();
  const auto bytes = ros::encode(std_msgs_msg_dds__Header__desc, &h);
  const std::vector<std::uint8_t> expected{0, 1, 0, 0, 1, 0, 0,   0,   2, 0,
                                           0, 0, 3, 0, 0, 0, 'a', 'b', 0};
  EXPECT_EQ(bytes, expected);
  std::string why;
  EXPECT_EQ(ros::header_stamp_ns(bytes.data(), bytes.size(), why), 1'000'000'002);
  // Big-endian CDR of the same header reads the same.
  const std::vector<std::uint8_t> be{0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 3, 'a', 'b', 0};
  EXPECT_EQ(ros::header_stamp_ns(be.data(), be.size(), why), 1'000'000'002);
  // Truncated inside the string, or not CDR at all.
  EXPECT_FALSE(ros::header_stamp_ns(bytes.data(), 17, why));
  EXPECT_NE(why.find("malformed or truncated"), std::string::npos) << why;
  const std::vector<std::uint8_t> xml{'<', '?', 'x', 'm', 'l'};
  EXPECT_FALSE(ros::header_stamp_ns(xml.data(), xml.size(), why));
  EXPECT_NE(why.find("encapsulation"), std::string::npos) << why;
}

// CameraInfo round trip for each distortion model.
TEST(RosBag, CameraInfoCarriesEveryDistortionModel) {
  io::Calibration plumb = testing::test_calibration(true), rational = plumb, fisheye = plumb;
  rational.rational = {0.01, -0.002, 0.0003};
  fisheye.fisheye = true;
  fisheye.dist = {0.1, -0.02, 0.003, -0.0004, 0.0};
  for (const io::Calibration& c : {plumb, rational, fisheye}) {
    const io::Calibration r = ros::decode_camera_info(ros::encode_camera_info(c, 5, "f"), "m");
    EXPECT_EQ(r.K, c.K);
    EXPECT_EQ(r.dist, c.dist);
    EXPECT_EQ(r.rational, c.rational);
    EXPECT_EQ(r.fisheye, c.fisheye);
    EXPECT_EQ(r.width, c.width);
    EXPECT_EQ(r.height, c.height);
  }
}

TEST(RosBag, BadBagsAreOneLineNamingTheFileAndWhatIsWrong) {
  const fs::path dir = test::scratch_dir("rosbag_bad");
  const fs::path folder = synth_folder(dir / "ds", 2, 3);
  sources::Dataset ds = sources::open_dataset(folder);
  sources::write_bag(ds, dir / "good");
  const auto copy = [&](const std::string& name) {
    fs::copy(dir / "good", dir / name, fs::copy_options::recursive);
    return dir / name;
  };
  const std::string meta = test::slurp(dir / "good" / "metadata.yaml");
  const std::string net = test::slurp(dir / "good" / "network.yaml");

  // A camera's topic that the bag does not have; a camera without a topic.
  const fs::path missing = copy("missing");
  test::write_text(missing / "network.yaml",
                   test::replaced(net, "/cam_2/image_raw", "/cam_9/image_raw"));
  expect_input_error([&] { sources::open_dataset(missing); },
                     {"network.yaml: cameras[1].image_topic: /cam_9/image_raw is not in the bag",
                      "/cam_1/image_raw, /cam_2/image_raw"});
  test::write_text(missing / "network.yaml",
                   test::replaced(net, "    image_topic: /cam_2/image_raw\n", ""));
  expect_input_error([&] { sources::open_dataset(missing); },
                     {"network.yaml: cameras[1].image_topic: missing", "metadata.yaml"});
  // Topics named in a folder that is not a bag.
  test::write_text(folder / "network.yaml", net);
  expect_input_error([&] { sources::open_dataset(folder); },
                     {"network.yaml: cameras[0].image_topic: only a rosbag2 bag's dataset"});

  // metadata.yaml disagreeing with the database.
  const fs::path counts = copy("counts");
  test::write_text(counts / "metadata.yaml",
                   test::replaced(meta, "message_count: 3\n", "message_count: 4\n"));
  expect_input_error([&] { ros::RosBag b(counts); },
                     {"metadata.yaml: topic /cam_1/image_raw", "3", "disagrees with the database"});
  // MCAP and compressed bags: how to convert.
  const fs::path mcap = copy("mcap");
  test::write_text(mcap / "metadata.yaml",
                   test::replaced(meta, "storage_identifier: sqlite3", "storage_identifier: mcap"));
  expect_input_error(
      [&] { sources::open_dataset(mcap); },
      {"metadata.yaml: rosbag2_bagfile_information.storage_identifier", "ros2 bag convert"});
  test::write_text(mcap / "metadata.yaml",
                   test::replaced(meta, "compression_format: \"\"", "compression_format: zstd"));
  expect_input_error([&] { ros::RosBag b(mcap); }, {"compression_format", "ros2 bag decompress"});

  // A truncated database.
  const fs::path cut = copy("cut");
  fs::resize_file(cut / "bag_0.db3", fs::file_size(cut / "bag_0.db3") / 3);
  expect_input_error([&] { ros::RosBag b(cut); }, {"bag_0.db3"});

  // An image of an encoding that is not read: the frame's read names the message.
  {
    ros::RosBagWriter w(dir / "bayer");
    const int t = w.add_topic("/cam_1/image_raw", ros::kImageType);
    w.write(t, 1'700'000'000'000'000'000, image_message("bayer_rggb8", 2, 2, 2, {1, 2, 3, 4}));
    w.close();
  }
  auto stream = sources::open_bag_topic(dir / "bayer", "/cam_1/image_raw", 0);
  expect_input_error([&] { stream->read(0); },
                     {"bayer:/cam_1/image_raw message 0 (", "bag_0.db3 row 1", "encoding"});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace netvmo
