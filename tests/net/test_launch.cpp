// netvmo launch (one process per camera, lock-step over Cyclone DDS) against netvmo run on a
// dataset rendered at test time: the merged outputs must be those of the in-process run.
#include <yaml-cpp/yaml.h>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "net_test_util.hpp"
#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/net/ros_publisher.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "test_util.hpp"

using namespace netvmo;
namespace fs = std::filesystem;

namespace {
using net_test::pose_at;
using net_test::read_csv;

constexpr int kFrames = 8;

// Largest difference between two CSVs of the same shape (numbers compared as numbers, other
// cells exactly); infinity when shapes or texts differ.
double csv_difference(const fs::path& a, const fs::path& b) {
  const auto ra = read_csv(a), rb = read_csv(b);
  if (ra.empty() || ra.size() != rb.size()) return INFINITY;
  double d = 0.0;
  for (size_t r = 0; r < ra.size(); ++r) {
    if (ra[r].size() != rb[r].size()) return INFINITY;
    for (size_t c = 0; c < ra[r].size(); ++c) {
      if (r == 0 || ra[r][c].empty() || rb[r][c].empty()) {
        if (ra[r][c] != rb[r][c]) return INFINITY;
        continue;
      }
      d = std::max(d, std::abs(std::stod(ra[r][c]) - std::stod(rb[r][c])));
    }
  }
  return d;
}

// Largest difference between two JSON documents' numbers (other values compared exactly).
double json_difference(const nlohmann::json& a, const nlohmann::json& b) {
  if (a.is_number() && b.is_number()) return std::abs(a.get<double>() - b.get<double>());
  if (a.type() != b.type() || a.size() != b.size()) return INFINITY;
  if (a.is_object()) {
    double d = 0.0;
    for (const auto& [k, v] : a.items()) {
      if (!b.contains(k)) return INFINITY;
      d = std::max(d, json_difference(v, b[k]));
    }
    return d;
  }
  if (a.is_array()) {
    double d = 0.0;
    for (size_t k = 0; k < a.size(); ++k) d = std::max(d, json_difference(a[k], b[k]));
    return d;
  }
  return a == b ? 0.0 : INFINITY;
}

class Launch : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::scratch_dir("launch"));
    const auto r = net_test::netvmo_bounded(
        "render " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml --frames " +
            std::to_string(kFrames) + " --out " + (*dir_ / "ds").string(),
        *dir_, 120);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static fs::path* dir_;
};
fs::path* Launch::dir_ = nullptr;

}  // namespace

// netvmo play: every image and calibration of the dataset on the camera topics, at their
// times, to a reliable reader (the images as they are: mono8 is lossless); best-effort writers
// reach a best-effort reader (a ROS 2 camera driver's QoS), each image received equal to its
// frame, and do not match a reliable one.
TEST_F(Launch, PlayPublishesEveryImageAndCameraInfo) {
  const fs::path ds = *dir_ / "ds";
  const int domain = net_test::loopback_domain(*dir_);
  auto source = sources::open_dataset_source(ds);
  const auto& cams = source->network().cameras;
  const auto readers = [&](bool reliable) {
    std::vector<std::unique_ptr<net::RosTopicReader>> r;
    for (const auto& c : cams) {
      const std::string p = "rt/cam_" + std::to_string(c.id);
      r.push_back(std::make_unique<net::RosTopicReader>(domain, p + "/image_raw",
                                                        ros::image_descriptor(), false, reliable));
      r.push_back(std::make_unique<net::RosTopicReader>(
          domain, p + "/camera_info", ros::camera_info_descriptor(), false, reliable));
    }
    return r;
  };
  // Each image message: its camera's frame at that stamp, pixel for pixel. Returns the count.
  const auto check_images = [&](net::RosTopicReader& r, size_t i) {
    int n = 0;
    for (const auto& m : r.take(1.0)) {
      std::string why;
      const auto ns = ros::header_stamp_ns(m.data(), m.size(), why);
      EXPECT_TRUE(ns.has_value()) << why;
      if (!ns) continue;
      const int f = static_cast<int>(std::llround(*ns * 1e-9 * source->network().fps));
      EXPECT_NEAR(*ns * 1e-9, source->frame_time(i, f), 1e-9);
      const cv::Mat got = ros::decode_gray(ros::kImageType, m, "image");
      EXPECT_EQ(cv::norm(got, source->read(i, f), cv::NORM_INF), 0.0) << "frame " << f;
      ++n;
    }
    return n;
  };
  {
    auto r = readers(true);
    const auto p =
        net_test::netvmo_bounded("play " + ds.string() + " --domain " + std::to_string(domain) +
                                     " --reliable --rate 0 --wait-readers 1 --quiet",
                                 *dir_, 120);
    ASSERT_EQ(p.code, 0) << p.out << p.err;
    for (size_t i = 0; i < cams.size(); ++i) {
      EXPECT_EQ(check_images(*r[2 * i], i), kFrames) << "camera " << cams[i].id;
      const auto infos = r[2 * i + 1]->take(1.0);
      EXPECT_EQ(infos.size(), static_cast<size_t>(kFrames));
      for (const auto& m : infos) {
        const auto calib = ros::decode_camera_info(m, "camera_info");
        EXPECT_EQ(calib.K, source->calibration(i).K);
      }
    }
  }
  {
    auto best_effort = readers(false);
    net::RosTopicReader reliable(domain, "rt/cam_1/image_raw", ros::image_descriptor());
    const auto p =
        net_test::netvmo_bounded("play " + ds.string() + " --domain " + std::to_string(domain) +
                                     " --rate 0 --wait-readers 1 --quiet --no-camera-info",
                                 *dir_, 120);
    ASSERT_EQ(p.code, 0) << p.out << p.err;
    int received = 0;
    for (size_t i = 0; i < cams.size(); ++i) received += check_images(*best_effort[2 * i], i);
    std::printf("best-effort play: %d of %d images received\n", received,
                kFrames * static_cast<int>(cams.size()));
    EXPECT_GE(received, 1);
    EXPECT_EQ(reliable.matched_writers(), 0);
    EXPECT_TRUE(reliable.take(0.2).empty());
  }
}

TEST_F(Launch, LockStepProcessesReproduceTheInProcessRun) {
  const fs::path ds = *dir_ / "ds", run = *dir_ / "run", launch = *dir_ / "launch";
  const int domain = net_test::loopback_domain(*dir_);
  const auto r1 =
      net_test::netvmo_bounded("run " + ds.string() + " --out " + run.string(), *dir_, 120);
  ASSERT_EQ(r1.code, 0) << r1.err;
  // A ROS 2-style subscriber of camera 1's average pose, started first.
  const pid_t ros = net::spawn({NETVMO_DDS_PEER, "ros", std::to_string(domain), "1",
                                std::to_string(kFrames), "60", (*dir_ / "ros.txt").string()},
                               *dir_ / "ros.log");
  // A subscriber of the rig's transforms and camera 1's measurements, started first too.
  const int cameras = 5, count = 5 * kFrames;
  const pid_t tf =
      net::spawn({NETVMO_DDS_PEER, "tf", std::to_string(domain), "1", std::to_string(cameras),
                  std::to_string(count), "60", (*dir_ / "tf.txt").string()},
                 *dir_ / "tf.log");
  for (int waited = 0; !fs::exists(*dir_ / "tf.txt.ready") && waited < 300; ++waited)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_TRUE(fs::exists(*dir_ / "tf.txt.ready")) << test::slurp(*dir_ / "tf.log");
  const auto r2 =
      net_test::netvmo_bounded("launch " + ds.string() + " --out " + launch.string() +
                                   " --domain " + std::to_string(domain) + " --timeout 90",
                               *dir_, 120);
  // Bounded past its own 60 s, so that it always writes what it received.
  const auto tf_result = net::supervise({tf}, 70.0, false);
  ASSERT_EQ(r2.code, 0) << r2.out << r2.err;
  EXPECT_TRUE(tf_result[0].finished && tf_result[0].exit_code == 0)
      << net::describe(tf_result[0]) << test::slurp(*dir_ / "tf.log");
  EXPECT_NE(r2.out.find("DDS domain " + std::to_string(domain) + ", loopback only"),
            std::string::npos)
      << r2.out;

  const auto ros_result = net::supervise({ros}, 10.0, false);
  EXPECT_TRUE(ros_result[0].finished && ros_result[0].exit_code == 0)
      << net::describe(ros_result[0]) << test::slurp(*dir_ / "ros.log");

  // The merged outputs are those of `netvmo run`.
  for (const char* f : {"estimates.csv", "energies.csv", "errors.csv"}) {
    const double d = csv_difference(run / f, launch / f);
    std::printf("%s: largest difference %.3g\n", f, d);
    EXPECT_LE(d, 1e-9) << f;
  }
  auto s_run = net_test::read_json(run / "summary.json"),
       s_launch = net_test::read_json(launch / "summary.json");
  s_run.erase("timing");
  s_launch.erase("timing");
  s_run.erase("warnings");
  s_launch.erase("warnings");
  const double ds_json = json_difference(s_run, s_launch);
  std::printf("summary.json: largest difference %.3g\n", ds_json);
  EXPECT_LE(ds_json, 1e-9);
  for (const char* f : {"energies.png", "errors.png", "overlays/mosaic.png", "overlays/mosaic.mp4",
                        "messages.json", "cyclonedds.xml", "nodes/node_3.log"})
    EXPECT_TRUE(fs::exists(launch / f)) << f;

  // Full precision: every node's estimates against the in-process run of the same options.
  auto source = sources::open_dataset_source(ds);
  run::ImageRunSettings o;
  o.progress = false;
  const auto res = run::run_images(*source, o);
  ASSERT_EQ(res.history.size(), static_cast<size_t>(kFrames));
  double worst = 0.0;
  const auto& cams = source->network().cameras;
  for (size_t i = 0; i < cams.size(); ++i) {
    const auto rows = read_csv(launch / "nodes" / ("node_" + std::to_string(cams[i].id) + ".csv"));
    ASSERT_EQ(rows.size(), static_cast<size_t>(kFrames + 1));
    for (int k = 0; k < kFrames; ++k) {
      const auto& row = rows[static_cast<size_t>(k + 1)];
      const auto& rec = res.history[static_cast<size_t>(k)].cameras[i];
      ASSERT_EQ(row.size(), 63u);
      EXPECT_EQ(row[2] == "1", rec.delta);
      EXPECT_EQ(row[37] == "1", rec.initialized);
      EXPECT_EQ(row[50] == "1", rec.indep_w.has_value());
      worst =
          std::max(worst, (pose_at(row, 38).matrix() - rec.est_w.matrix()).cwiseAbs().maxCoeff());
      if (rec.indep_w)
        worst = std::max(worst,
                         (pose_at(row, 51).matrix() - rec.indep_w->matrix()).cwiseAbs().maxCoeff());
    }
  }
  std::printf("node estimates vs in-process run: largest difference %.3g\n", worst);

  // Camera 1's geometry_msgs/msg/PoseStamped messages carry its estimate of each frame (the
  // first ones may go out before the subscriber is discovered).
  {
    std::ifstream in(*dir_ / "ros.txt");
    const auto rows = read_csv(launch / "nodes" / "node_1.csv");
    int count = 0;
    std::string frame_id;
    long sec = 0;
    unsigned long nsec = 0;
    double p[3], q[4];
    while (in >> sec >> nsec >> frame_id >> p[0] >> p[1] >> p[2] >> q[0] >> q[1] >> q[2] >> q[3]) {
      ++count;
      EXPECT_EQ(frame_id, "world");
      const int k = static_cast<int>(std::lround((sec + nsec * 1e-9) * source->network().fps));
      ASSERT_GE(k, 0);
      ASSERT_LT(k, kFrames);
      const obs::SE3 est = pose_at(rows[static_cast<size_t>(k + 1)], 38);
      EXPECT_EQ((obs::Vec3(p[0], p[1], p[2]) - est.translation()).cwiseAbs().maxCoeff(), 0.0);
      const Eigen::Quaterniond qq(q[0], q[1], q[2], q[3]);
      EXPECT_LT((qq.toRotationMatrix() - est.linear()).cwiseAbs().maxCoeff(), 1e-12);
    }
    EXPECT_GE(count, 1) << "no PoseStamped received";
    std::printf("PoseStamped samples of camera 1: %d of %d frames\n", count, kFrames);
  }
  EXPECT_LE(worst, 1e-9);
  // Blind cameras 4 and 5 are initialised within the first frame (through their neighbours).
  for (const auto& c : res.history[0].cameras) EXPECT_TRUE(c.initialized);

  // Message statistics: every round's estimate sent, nothing malformed or out of order.
  const auto messages = net_test::read_json(launch / "messages.json");
  for (const auto& c : cams) {
    const auto& m = messages[std::to_string(c.id)];
    EXPECT_EQ(m["sent"].get<int>(), kFrames * res.substeps);
    EXPECT_EQ(m["late"].get<int>(), 0);
    for (const auto& [k, v] : m["rejected"].items())
      if (k != "not a neighbour") {
        EXPECT_EQ(v.get<int>(), 0) << k;
      }
  }

  // `netvmo merge`: the nodes' files gathered into one folder (as from several machines) merge
  // into the launch's outputs; a missing node output or nodes run with different options give
  // one line naming the file.
  const fs::path gathered = *dir_ / "gathered", merged = *dir_ / "merged";
  fs::create_directories(gathered);
  for (const auto& c : cams)
    for (const char* ext : {".csv", ".json"}) {
      const std::string f = "node_" + std::to_string(c.id) + ext;
      fs::copy_file(launch / "nodes" / f, gathered / f);
    }
  const auto m = net_test::netvmo_bounded(
      "merge " + gathered.string() + " --dataset " + ds.string() + " --out " + merged.string(),
      *dir_, 60);
  ASSERT_EQ(m.code, 0) << m.out << m.err;
  for (const char* f : {"estimates.csv", "energies.csv", "errors.csv"})
    EXPECT_EQ(csv_difference(launch / f, merged / f), 0.0) << f;
  auto s_merged = net_test::read_json(merged / "summary.json");
  s_merged.erase("timing");
  s_merged.erase("warnings");
  EXPECT_EQ(json_difference(s_launch, s_merged), 0.0);
  EXPECT_EQ(net_test::read_json(merged / "messages.json"), messages);
  for (const char* f : {"energies.png", "overlays/mosaic.png"})
    EXPECT_TRUE(fs::exists(merged / f)) << f;

  auto j2 = net_test::read_json(gathered / "node_2.json");
  j2["options"]["k_s"] = 7.0;
  std::ofstream(gathered / "node_2.json") << j2.dump();
  const auto bad = net_test::netvmo_bounded("merge " + gathered.string() + " --dataset " +
                                                ds.string() + " --out " + (*dir_ / "bad").string(),
                                            *dir_, 60);
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find((gathered / "node_2.json").string() + ": options:"), std::string::npos)
      << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  // A gathered node_2.json without its warnings, or with its messages not an object: one line
  // naming the file and the key.
  for (const char* key : {"warnings", "messages"}) {
    auto j = net_test::read_json(launch / "nodes" / "node_2.json");
    if (std::string(key) == "warnings")
      j.erase(key);
    else
      j[key] = 3;
    std::ofstream(gathered / "node_2.json") << j.dump();
    const auto r = net_test::netvmo_bounded("merge " + gathered.string() + " --dataset " +
                                                ds.string() + " --out " + (*dir_ / "bad").string(),
                                            *dir_, 60);
    EXPECT_NE(r.code, 0) << key;
    EXPECT_NE(r.err.find((gathered / "node_2.json").string() + ": " + key + ": missing or not"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  fs::copy_file(launch / "nodes" / "node_2.json", gathered / "node_2.json",
                fs::copy_options::overwrite_existing);
  // A gathered node_2.csv damaged in one field (line 3's status, its fifth column, made 9): one
  // line naming the file, the line and the column, and nothing written.
  {
    std::string text = test::slurp(gathered / "node_2.csv");
    size_t at = 0;
    for (int n = 0; n < 2; ++n) at = text.find('\n', at) + 1;  // line 3's start
    for (int n = 0; n < 4; ++n) at = text.find(',', at) + 1;   // its fifth field
    text.replace(at, text.find(',', at) - at, "9");
    test::write_text(gathered / "node_2.csv", text);
    const auto r = net_test::netvmo_bounded("merge " + gathered.string() + " --dataset " +
                                                ds.string() + " --out " + (*dir_ / "bad").string(),
                                            *dir_, 60);
    EXPECT_NE(r.code, 0);
    test::expect_one_line(r.err, {(gathered / "node_2.csv").string() + ":3: status: expected a "
                                                                       "status 0..6, got '9'"});
    EXPECT_FALSE(fs::exists(*dir_ / "bad"));
    fs::copy_file(launch / "nodes" / "node_2.csv", gathered / "node_2.csv",
                  fs::copy_options::overwrite_existing);
  }
  fs::remove(gathered / "node_3.csv");
  const auto missing =
      net_test::netvmo_bounded("merge " + gathered.string() + " --dataset " + ds.string() +
                                   " --out " + (*dir_ / "bad").string(),
                               *dir_, 60);
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.err.find((gathered / "node_3.csv").string() + ": not found"), std::string::npos)
      << missing.err;
  EXPECT_FALSE(fs::exists(*dir_ / "bad" / "estimates.csv"));

  // The separate subscriber's rt/tf_static: world -> cam_<id>, each camera's network.yaml pose;
  // rt/tf: world -> cam_1/average_pose, the estimate of node_1.csv at that frame; camera 1's
  // measurements: its PnP pose in the camera frame with a covariance (symmetric, positive
  // definite, its position sd below a centimetre at these distances).
  {
    std::ifstream in(*dir_ / "tf.txt");
    const auto rows = read_csv(launch / "nodes" / "node_1.csv");
    std::set<std::string> statics;
    int tf1 = 0, measurements = 0;
    std::string kind, line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      long long ns = 0;
      ls >> kind >> ns;
      const int k = static_cast<int>(std::llround(ns * 1e-9 * source->network().fps));
      std::string parent, child;
      double p[3], q[4];
      if (kind == "static" || kind == "tf") ls >> parent >> child;
      if (kind == "measurement") ls >> parent;
      ls >> p[0] >> p[1] >> p[2] >> q[0] >> q[1] >> q[2] >> q[3];
      ASSERT_TRUE(ls) << line;
      obs::SE3 g = obs::SE3::Identity();
      g.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
      g.translation() = obs::Vec3(p[0], p[1], p[2]);
      if (kind == "static") {
        EXPECT_EQ(parent, "world");
        statics.insert(child);
        for (const auto& c : cams) {
          if (child == "cam_" + std::to_string(c.id)) {
            EXPECT_LT((g.matrix() - c.g_wi.matrix()).cwiseAbs().maxCoeff(), 1e-12) << child;
          }
        }
      } else if (kind == "tf" && child == "cam_1/average_pose") {
        ++tf1;
        ASSERT_GE(k, 0);
        ASSERT_LT(k, kFrames);
        const auto& row = rows[static_cast<size_t>(k + 1)];
        EXPECT_EQ(row[37], "1");
        EXPECT_LT((g.matrix() - pose_at(row, 38).matrix()).cwiseAbs().maxCoeff(), 1e-12);
      } else if (kind == "measurement") {
        ++measurements;
        EXPECT_EQ(parent, "cam_1");
        ASSERT_GE(k, 0);
        ASSERT_LT(k, kFrames);
        const auto& row = rows[static_cast<size_t>(k + 1)];
        EXPECT_EQ(row[24], "1");
        EXPECT_LT((g.matrix() - pose_at(row, 25).matrix()).cwiseAbs().maxCoeff(), 1e-12);
        Eigen::Matrix<double, 6, 6> C;
        for (int a = 0; a < 36; ++a) ls >> C(a / 6, a % 6);
        ASSERT_TRUE(ls) << line;
        EXPECT_LT((C - C.transpose()).cwiseAbs().maxCoeff(), 1e-15);
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(C);
        EXPECT_GT(eig.eigenvalues()(0), 0.0);
        EXPECT_LT(std::sqrt(C.topLeftCorner<3, 3>().trace()), 0.01);
      }
    }
    EXPECT_EQ(statics.size(), cams.size());
    std::printf(
        "ROS 2 subscriber: %zu static transforms, %d of camera 1's estimate transforms, "
        "%d measurements\n",
        statics.size(), tf1, measurements);
    // The first ones may go out before the subscriber is found (tf_static, transient-local,
    // reaches it whenever it is).
    EXPECT_GE(tf1, 1);
    EXPECT_GE(measurements, 1);
  }
}

// A rosbag2 bag of the same dataset (netvmo bag, PNG CompressedImage and CameraInfo topics)
// launched lock-step: every node opens only its camera's topic, all on the same time origin,
// and the merged estimates are `netvmo run`'s on the folder.
TEST_F(Launch, ABagLaunchesAsItsFolderRuns) {
  const fs::path ds = *dir_ / "ds", bag = *dir_ / "bag", run = *dir_ / "run_for_bag",
                 launch = *dir_ / "launch_bag";
  const auto b = net_test::netvmo_bounded(
      "bag " + ds.string() + " --out " + bag.string() + " --encoding png", *dir_, 120);
  ASSERT_EQ(b.code, 0) << b.err;
  const auto r1 =
      net_test::netvmo_bounded("run " + ds.string() + " --out " + run.string(), *dir_, 120);
  ASSERT_EQ(r1.code, 0) << r1.err;
  const int domain = net_test::loopback_domain(*dir_);
  const auto r2 =
      net_test::netvmo_bounded("launch " + bag.string() + " --out " + launch.string() +
                                   " --domain " + std::to_string(domain) + " --timeout 90",
                               *dir_, 120);
  ASSERT_EQ(r2.code, 0) << r2.out << r2.err;
  for (const char* f : {"estimates.csv", "energies.csv", "errors.csv"})
    EXPECT_EQ(csv_difference(run / f, launch / f), 0.0) << f;
}

// The zero-offset estimator as processes: its consensus state (x_i, eta_i: 26 values) crosses
// DDS in the Estimate type, so a lock-step launch with --estimator zero-offset equals `netvmo run
// --estimator zero-offset` bit for bit, and differs from the paper's observer (the estimator
// reached the nodes).
TEST_F(Launch, ZeroOffsetProcessesReproduceTheInProcessRun) {
  const fs::path ds = *dir_ / "ds", run = *dir_ / "run_zero", vmo = *dir_ / "run_vmo",
                 launch = *dir_ / "launch_zero";
  const int domain = net_test::loopback_domain(*dir_);
  const auto r1 = net_test::netvmo_bounded(
      "run " + ds.string() + " --estimator zero-offset --out " + run.string(), *dir_, 120);
  ASSERT_EQ(r1.code, 0) << r1.err;
  const auto r2 =
      net_test::netvmo_bounded("run " + ds.string() + " --out " + vmo.string(), *dir_, 120);
  ASSERT_EQ(r2.code, 0) << r2.err;
  const auto r3 = net_test::netvmo_bounded(
      "launch " + ds.string() + " --estimator zero-offset --out " + launch.string() + " --domain " +
          std::to_string(domain) + " --timeout 90 --no-overlays --no-plots",
      *dir_, 120);
  ASSERT_EQ(r3.code, 0) << r3.out << r3.err;
  for (const char* f : {"estimates.csv", "energies.csv", "errors.csv"})
    EXPECT_EQ(csv_difference(run / f, launch / f), 0.0) << f;
  EXPECT_GT(csv_difference(vmo / "estimates.csv", launch / "estimates.csv"), 1e-6);
  EXPECT_EQ(net_test::read_json(launch / "nodes" / "node_1.json")["options"]["estimator"],
            "zero-offset");
}

TEST_F(Launch, AFailingNodeFailsTheLaunchWithOneClearLine) {
  // Camera 3's frame 2 is corrupt: its node stops, the launcher stops the others.
  const fs::path ds = *dir_ / "ds_bad";
  fs::copy(*dir_ / "ds", ds, fs::copy_options::recursive);
  std::ofstream(ds / "cam_3" / "000002.png") << "not a png";
  const int domain = net_test::loopback_domain(*dir_);
  const auto r = net_test::netvmo_bounded(
      "launch " + ds.string() + " --out " + (*dir_ / "bad").string() + " --domain " +
          std::to_string(domain) + " --timeout 60 --node-timeout 5",
      *dir_, 90);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("node of camera 3 failed (exit 1)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("000002.png"), std::string::npos) << r.err;
}

TEST_F(Launch, ANodeNamesItsSilentNeighbour) {
  // Camera 4 alone: its neighbours (cameras 3 and 5) never speak.
  const int domain = net_test::loopback_domain(*dir_);
  const auto r = net_test::netvmo_bounded("node " + (*dir_ / "ds").string() + " --camera 4 --out " +
                                              (*dir_ / "alone").string() + " --domain " +
                                              std::to_string(domain) + " --timeout 1",
                                          *dir_, 60);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("netvmo node: error: camera 4: no message of round 1 from neighbour camera"),
            std::string::npos)
      << r.err;
}

// A node of one camera (camera 1 of the render, no neighbours) on its frames as rendered, then
// on the same frames halved and doubled by nearest neighbour: the second warns once, on stderr
// and in node_<id>.json's warnings; the first, whose images have enough pairs on steep edges to
// be judged (asserted), does not.
TEST_F(Launch, ANodeWarnsOnceOfResampledFrames) {
  const int domain = net_test::loopback_domain(*dir_);
  io::NetworkConfig net = io::load_network_config(*dir_ / "ds" / "network.yaml");
  net.cameras.resize(1);
  net.edges.clear();
  const std::string warning = "camera 1: its images look resampled by nearest neighbour";
  for (const bool resampled : {false, true}) {
    const fs::path ds = *dir_ / (resampled ? "one_resampled" : "one");
    fs::create_directories(ds / "calib");
    fs::copy(*dir_ / "ds" / "calib" / "cam_1.yaml", ds / "calib" / "cam_1.yaml");
    test::write_text(ds / "network.yaml", io::network_yaml(net));
    fs::create_directories(ds / "cam_1");
    for (const auto& e : fs::directory_iterator(*dir_ / "ds" / "cam_1")) {
      cv::Mat img = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(img.empty()) << e.path();
      if (resampled) {
        cv::Mat half;
        cv::resize(img, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
        cv::resize(half, img, img.size(), 0.0, 0.0, cv::INTER_NEAREST);
      }
      const auto m = frontend::measure_resampling(img);
      EXPECT_GE(m.pairs, frontend::ResamplingSettings().min_pairs) << e.path();
      EXPECT_EQ(m.nearest_neighbour, resampled) << e.path() << ": " << m.repeated;
      ASSERT_TRUE(cv::imwrite((ds / "cam_1" / e.path().filename()).string(), img));
    }
    const fs::path out = ds.string() + "_out";
    const auto r =
        net_test::netvmo_bounded("node " + ds.string() + " --camera 1 --domain " +
                                     std::to_string(domain) + " --no-plots --out " + out.string(),
                                 *dir_, 120);
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const auto count = [&](const std::string& s) {
      int n = 0;
      for (size_t at = s.find(warning); at != std::string::npos; at = s.find(warning, at + 1)) ++n;
      return n;
    };
    EXPECT_EQ(count(r.err), resampled ? 1 : 0) << r.err;
    const auto j = net_test::read_json(out / "node_1.json");
    EXPECT_EQ(count(j.at("warnings").dump()), resampled ? 1 : 0) << j.at("warnings").dump();
  }
}

// --ros-wait-readers: a node waits for the readers of its average_pose topic before its first
// frame, at most --timeout, then fails with one line naming the topic; with a reader there it
// goes on (camera 4 alone: it then fails in round 1, naming its silent neighbour).
TEST_F(Launch, ANodeWaitsForItsPoseReadersAndNamesTheTopicWhenNoneComes) {
  const int domain = net_test::loopback_domain(*dir_);
  const std::string node = "node " + (*dir_ / "ds").string() + " --camera 4 --domain " +
                           std::to_string(domain) + " --timeout 2 --ros-wait-readers 1 --out ";
  const auto none = net_test::netvmo_bounded(node + (*dir_ / "none").string(), *dir_, 60);
  EXPECT_EQ(none.code, 1);
  test::expect_one_line(none.err, {"rt/netvmo/camera_4/average_pose", "1 reader(s)",
                                   "did not come within 2 s", "--ros-wait-readers"});
  // With a reader: past the wait, to the neighbours' silence.
  net::RosTopicReader reader(domain, "rt/netvmo/camera_4/average_pose",
                             ros::pose_stamped_descriptor());
  const auto with = net_test::netvmo_bounded(node + (*dir_ / "with").string(), *dir_, 60);
  EXPECT_EQ(with.code, 1);
  EXPECT_EQ(with.err.find("average_pose"), std::string::npos) << with.err;
  EXPECT_NE(with.err.find("no message of round 1 from neighbour camera"), std::string::npos)
      << with.err;
}

TEST_F(Launch, NodesWhoseGraphsDifferStopNamingBothCameras) {
  // Cameras 4 and 5 are neighbours; camera 5's copy of network.yaml has one more edge (2, 5).
  const fs::path other = *dir_ / "ds_graph";
  fs::copy(*dir_ / "ds", other, fs::copy_options::recursive);
  YAML::Node net = YAML::LoadFile((other / "network.yaml").string());
  ASSERT_TRUE(net["edges"].IsSequence());
  YAML::Node edge(YAML::NodeType::Sequence);
  edge.push_back(2);
  edge.push_back(5);
  net["edges"].push_back(edge);
  std::ofstream(other / "network.yaml") << YAML::Dump(net) << "\n";
  const int domain = net_test::loopback_domain(*dir_);
  const auto node = [&](const fs::path& ds, int camera) {
    return std::vector<std::string>{std::string(NETVMO_BINARY_DIR) + "/netvmo",
                                    "node",
                                    ds.string(),
                                    "--camera",
                                    std::to_string(camera),
                                    "--out",
                                    (*dir_ / ("graph_" + std::to_string(camera))).string(),
                                    "--domain",
                                    std::to_string(domain),
                                    "--timeout",
                                    "3"};
  };
  // Not stopped when the first fails: each must stop on its own (bounded: killed after 40 s).
  const std::vector<pid_t> pids = {net::spawn(node(*dir_ / "ds", 4), *dir_ / "graph_4.log"),
                                   net::spawn(node(other, 5), *dir_ / "graph_5.log")};
  const auto res = net::supervise(pids, 40.0, false);
  int named = 0;
  for (int k = 0; k < 2; ++k) {
    const int me = 4 + k, them = 5 - k;
    EXPECT_TRUE(res[static_cast<size_t>(k)].finished) << net::describe(res[static_cast<size_t>(k)]);
    EXPECT_NE(res[static_cast<size_t>(k)].exit_code, 0);
    const std::string log = test::slurp(*dir_ / ("graph_" + std::to_string(me) + ".log"));
    const std::string line = "netvmo node: error: camera " + std::to_string(me) + " and camera " +
                             std::to_string(them) + ": their network.yaml graphs differ";
    if (log.find(line) != std::string::npos)
      ++named;
    else
      std::printf("camera %d:\n%s\n", me, log.c_str());
  }
  // The first to stop may leave before its message reaches the other (which then times out).
  EXPECT_GE(named, 1);
}

namespace {
// Processes (other than `except`) whose command line mentions `text`.
std::vector<pid_t> processes_mentioning(const std::string& text, pid_t except) {
  std::vector<pid_t> found;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), ::isdigit)) continue;
    std::ifstream in(e.path() / "cmdline", std::ios::binary);
    const std::string cmdline((std::istreambuf_iterator<char>(in)), {});
    const pid_t pid = static_cast<pid_t>(std::stol(name));
    if (pid != except && cmdline.find(text) != std::string::npos) found.push_back(pid);
  }
  return found;
}
}  // namespace

TEST_F(Launch, AKilledLaunchLeavesNoNodeRunning) {
  // launch is killed with SIGKILL while its five nodes run (async, paced at 1/20 of real time:
  // 8 frames last ~5 s): every node must be gone within 2 s, long before its own end.
  const int domain = net_test::loopback_domain(*dir_);
  const fs::path out = *dir_ / "killed_launch";
  const pid_t launch =
      net::spawn({std::string(NETVMO_BINARY_DIR) + "/netvmo", "launch", (*dir_ / "ds").string(),
                  "--out", out.string(), "--mode", "async", "--speed", "0.05", "--domain",
                  std::to_string(domain), "--timeout", "60", "--no-overlays", "--no-plots"},
                 *dir_ / "killed_launch.log");
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(clock::now() - t0).count(); };
  size_t nodes = 0;
  while (seconds() < 30 && (nodes = processes_mentioning(out.string(), launch).size()) < 5)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (nodes == 5u) std::this_thread::sleep_for(std::chrono::milliseconds(500));  // running
  const size_t running = processes_mentioning(out.string(), launch).size();
  ::kill(launch, SIGKILL);  // on every path: the test never leaves launch behind
  int status = 0;
  ::waitpid(launch, &status, 0);
  ASSERT_EQ(nodes, 5u) << "the nodes did not start in 30 s";
  ASSERT_EQ(running, 5u) << "a node ended early";
  const double killed = seconds();
  std::vector<pid_t> left;
  while ((left = processes_mentioning(out.string(), launch)).size() > 0 && seconds() < killed + 2)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(left.empty()) << left.size() << " node(s) still running 2 s after launch was killed";
  for (pid_t p : left) ::kill(p, SIGKILL);  // bounded either way
}
