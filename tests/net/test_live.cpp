// Live camera topics (docs/ros2.md, "Live camera topics"): a rendered dataset played as ROS 2
// camera topics (`netvmo play`) and read by one node per camera (`netvmo launch --live`), against
// `netvmo launch --mode async` on the folder itself, on a render of paper5_render.yaml (30 frames,
// k_e = 10, k_s = 100, --speed 0.25 and play --rate 0.25).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <thread>

#include "net_test_util.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/net/live_camera.hpp"
#include "netvmo/pipeline/net/play.hpp"
#include "netvmo/pipeline/net/socket_drops.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "netvmo/pipeline/sources/topic_network.hpp"

using namespace netvmo;
namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 30;
// node_<id>.csv's columns: delta .. the PnP pose (the front end's result), the networked
// estimate's initialized flag and pose.
constexpr size_t kDelta = 2, kPnpEnd = 37, kInitialized = 37, kEstimate = 38;

const std::string kGains = " --ke 10 --ks 100 --no-plots --timeout 100 ";

// `dir`/name: network.yaml of `ds` with each camera's image topic /cam_<id>/image_raw + `suffix`
// (and its camera info topic, with `camera_info`), and ds's calib/ unless `camera_info`.
fs::path live_folder(const fs::path& ds, const fs::path& dir, const std::string& name,
                     const std::string& suffix, bool camera_info) {
  const fs::path f = dir / name;
  fs::create_directories(f);
  io::NetworkConfig net = io::load_network_config(ds / "network.yaml");
  for (auto& c : net.cameras) {
    const std::string p = "/cam_" + std::to_string(c.id);
    c.image_topic = p + "/image_raw" + suffix;
    if (camera_info) c.camera_info_topic = p + "/camera_info";
  }
  test::write_text(f / "network.yaml", io::network_yaml(net));
  if (!camera_info) fs::copy(ds / "calib", f / "calib");
  return f;
}

// `netvmo READER_ARGS` (a live node or launch, bounded by reader_s) run on a thread while
// `netvmo play PLAY_ARGS` (bounded by play_s) publishes; their logs in logs/reader and logs/play.
struct PlayedTo {
  test::CliResult reader, play;
};
PlayedTo play_to(const std::string& reader_args, int reader_s, const std::string& play_args,
                 int play_s, const fs::path& logs) {
  fs::create_directories(logs / "reader");
  fs::create_directories(logs / "play");
  PlayedTo r;
  std::thread t(
      [&] { r.reader = net_test::netvmo_bounded(reader_args, logs / "reader", reader_s); });
  r.play = net_test::netvmo_bounded("play " + play_args, logs / "play", play_s);
  t.join();
  return r;
}

// `launch FOLDER --live` into `out` while `play DS` publishes (waiting for the nodes' readers).
void live_launch(const fs::path& dir, const fs::path& folder, const fs::path& ds,
                 const fs::path& out, int domain, const std::string& play_args) {
  const auto r =
      play_to("launch " + folder.string() + " --live --domain " + std::to_string(domain) +
                  " --speed 0.25 --lag 0.3" + kGains + "--out " + out.string(),
              150,
              ds.string() + " --domain " + std::to_string(domain) +
                  " --rate 0.25 --wait-readers 1 --timeout 90 --quiet " + play_args,
              120, dir / (out.filename().string() + "_logs"));
  EXPECT_EQ(r.play.code, 0) << r.play.out << r.play.err;
  ASSERT_EQ(r.reader.code, 0) << r.reader.out << r.reader.err;
}

// Largest differences between the two runs' estimates over every camera: over the first ten
// frames, the last ten, and at the last frame.
struct Difference {
  double first_m = 0, first_deg = 0, late_m = 0, late_deg = 0, last_m = 0, last_deg = 0;
};

// The frames of camera `i` of `ds` whose image time no row of a node's CSV has (to say which a
// short node missed).
std::string missing_frames(const std::vector<std::vector<std::string>>& rows,
                           const sources::NetworkSource& ds, size_t i) {
  std::string out = "frames without a row:";
  for (int k = 0; k < kFrames; ++k) {
    bool found = false;
    for (size_t r = 1; r < rows.size() && !found; ++r)
      found = rows[r].size() > 1 && std::abs(std::stod(rows[r][1]) - ds.frame_time(i, k)) < 1e-9;
    if (!found) out += " " + std::to_string(k);
  }
  return out;
}

// The live nodes' rows against the async launch's: the same image times, the same front-end
// results cell for cell (the same images and calibration), and the estimates' largest and last
// differences over every camera.
Difference compare_nodes(const fs::path& live, const fs::path& async, const io::NetworkConfig& net,
                         const sources::NetworkSource& ds) {
  Difference d;
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    const std::string f = "node_" + std::to_string(net.cameras[i].id) + ".csv";
    const auto l = net_test::read_csv(live / "nodes" / f),
               a = net_test::read_csv(async / "nodes" / f);
    EXPECT_EQ(l.size(), static_cast<size_t>(kFrames + 1))
        << live / "nodes" / f << ": " << missing_frames(l, ds, i);
    EXPECT_EQ(a.size(), static_cast<size_t>(kFrames + 1)) << async / "nodes" / f;
    if (l.size() != a.size()) continue;
    for (size_t r = 1; r < l.size(); ++r) {
      const int k = static_cast<int>(r) - 1;
      EXPECT_NEAR(std::stod(l[r][1]), ds.frame_time(i, k), 1e-9) << f << " row " << r;
      for (size_t c = kDelta; c < kPnpEnd; ++c)
        EXPECT_EQ(l[r][c], a[r][c]) << f << " row " << r << " column " << c;
      EXPECT_EQ(l[r][kInitialized], a[r][kInitialized]) << f << " row " << r;
      const obs::SE3 gl = net_test::pose_at(l[r], kEstimate),
                     ga = net_test::pose_at(a[r], kEstimate);
      const double m = (gl.translation() - ga.translation()).norm();
      const double deg =
          Eigen::AngleAxisd(gl.linear().transpose() * ga.linear()).angle() * 180.0 / M_PI;
      if (k < 10) {
        d.first_m = std::max(d.first_m, m);
        d.first_deg = std::max(d.first_deg, deg);
      }
      if (k >= kFrames - 10) {
        d.late_m = std::max(d.late_m, m);
        d.late_deg = std::max(d.late_deg, deg);
      }
      if (r + 1 == l.size()) {
        d.last_m = std::max(d.last_m, m);
        d.last_deg = std::max(d.last_deg, deg);
      }
    }
  }
  return d;
}

class Live : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::scratch_dir("live"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

// The tolerance. Both runs are asynchronous: each node integrates its frames on its own and takes
// its neighbours' latest estimates as they come, so two runs differ in when the first messages
// arrive (which depends on the processes' start, not on the input), and the difference then
// contracts with the consensus, by ~15 % per frame here. Two async launches of this dataset
// differed by 8.6 mm and 0.21 deg at the first frame and 0.07 mm at the last; live against async,
// in eight runs (three under stress-ng --cpu 2), 4.8-32.5 mm and 0.2-0.9 deg over the first ten
// frames, 0.18-1.24 mm over the last ten, and 0.05-0.28 mm and 0.005-0.010 deg at the last
// (2026-12-02). Asserted: the front end's results equal cell for cell (the same images and
// calibrations), the estimates' difference over the last ten frames at most a quarter of that
// over the first ten (the transient decays), and at the last frame within 1 mm and 0.05 deg.
TEST_F(Live, PlayedTopicsGiveTheAsyncLaunchsEstimates) {
  const fs::path dir = dir_;
  auto r = net_test::netvmo_bounded("render " + std::string(NETVMO_SOURCE_DIR) +
                                        "/datasets/paper5_render.yaml --frames " +
                                        std::to_string(kFrames) + " --out " + (dir / "ds").string(),
                                    dir, 120);
  ASSERT_EQ(r.code, 0) << r.err;
  const int domain = net_test::loopback_domain(dir);
  auto ds = sources::open_dataset_source(dir / "ds");
  const auto& net = ds->network();
  r = net_test::netvmo_bounded("launch " + (dir / "ds").string() + " --mode async --domain " +
                                   std::to_string(domain) + " --speed 0.25 --no-overlays" + kGains +
                                   "--out " + (dir / "async").string(),
                               dir, 150);
  ASSERT_EQ(r.code, 0) << r.out << r.err;

  // Raw mono8 images from reliable writers; calib/ files.
  live_launch(dir, live_folder(dir / "ds", dir, "live_raw", "", false), dir / "ds", dir / "raw",
              domain, "--reliable");
  // PNG CompressedImage from best-effort writers (a camera driver's QoS); every calibration
  // from the first CameraInfo.
  live_launch(dir, live_folder(dir / "ds", dir, "live_png", "/compressed", true), dir / "ds",
              dir / "png", domain, "--encoding png");
  for (const char* run : {"raw", "png"}) {
    const Difference d = compare_nodes(dir / run, dir / "async", net, *ds);
    std::printf(
        "%s: live against async: first ten frames %.2f mm and %.3f deg, last ten %.3f mm "
        "and %.4f deg, last frame %.3f mm and %.4f deg\n",
        run, d.first_m * 1e3, d.first_deg, d.late_m * 1e3, d.late_deg, d.last_m * 1e3, d.last_deg);
    EXPECT_LE(d.late_m, d.first_m / 4) << run;
    EXPECT_LE(d.late_deg, d.first_deg / 4) << run;
    EXPECT_LT(d.last_m, 0.001) << run;
    EXPECT_LT(d.last_deg, 0.05) << run;
    // The merged outputs of any launch, on the grid of the images' times.
    const auto s = net_test::read_json(dir / run / "summary.json");
    EXPECT_EQ(s["frames"].get<int>(), kFrames) << run;
    const auto m = net_test::read_json(dir / run / "messages.json");
    for (const auto& c : net.cameras)
      EXPECT_GT(m[std::to_string(c.id)]["received"].get<int>(), 0) << run << " camera " << c.id;
    const auto node = net_test::read_json(dir / run / "nodes" / "node_1.json");
    EXPECT_EQ(node["image_topic"].get<std::string>(),
              std::string("/cam_1/image_raw") + (run == std::string("png") ? "/compressed" : ""));
  }
}

// `f`: a live folder of one camera (id 1) on /cam_1/image_raw, with its calibration.
static void one_topic_folder(const fs::path& f) {
  fs::create_directories(f / "calib");
  test::write_text(f / "network.yaml",
                   "fps: 30\ntarget: {family: tag36h11, id: 0, size: 0.2}\ncameras:\n"
                   "  - {id: 1, p_wi: [0, 0, 1], r_wi: [0, 0, 0], image_topic: /cam_1/image_raw}\n"
                   "edges: []\n");
  test::write_text(f / "calib" / "cam_1.yaml",
                   "image_width: 64\nimage_height: 48\ncamera_name: cam_1\n"
                   "camera_matrix: {rows: 3, cols: 3, data: [50, 0, 32, 0, 50, 24, 0, 0, 1]}\n"
                   "distortion_model: plumb_bob\n"
                   "distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n");
}

// A topic nobody publishes fails the node after --timeout with one line naming it; a live folder
// whose camera names no topic, and a live lock-step launch, are refused in one line.
TEST_F(Live, BadLiveInputIsOneLine) {
  const fs::path dir = dir_;
  const fs::path f = dir / "f";
  fs::create_directories(f / "calib");
  test::write_text(f / "network.yaml",
                   "fps: 30\ntarget: {family: tag36h11, id: 0, size: 0.2}\ncameras:\n"
                   "  - {id: 1, p_wi: [0, 0, 1], r_wi: [0, 0, 0], image_topic: /cam_1/image_raw}\n"
                   "  - {id: 2, p_wi: [1, 0, 1], r_wi: [0, 0, 0]}\nedges:\n  - [1, 2]\n");
  auto r = net_test::netvmo_bounded(
      "launch " + f.string() + " --live --out " + (dir / "o").string(), dir, 60);
  EXPECT_NE(r.code, 0);
  test::expect_one_line(r.err, {"network.yaml", "cameras[1].image_topic: missing"});
  r = net_test::netvmo_bounded(
      "launch " + f.string() + " --live --mode lockstep --out " + (dir / "o").string(), dir, 60);
  EXPECT_NE(r.code, 0);
  test::expect_one_line(r.err, {"--live", "--mode async"});
  // Camera 1 alone (its neighbour's node is not needed to fail on its silent topic: a node
  // without neighbours' writers fails on them first, so camera 2 is left out of the network).
  one_topic_folder(f);
  const int domain = net_test::loopback_domain(dir);
  r = net_test::netvmo_bounded("node " + f.string() + " --camera 1 --live --domain " +
                                   std::to_string(domain) + " --timeout 1 --out " +
                                   (dir / "n").string(),
                               dir, 60);
  EXPECT_NE(r.code, 0);
  test::expect_one_line(r.err, {"/cam_1/image_raw", "no image within"});
}

// Images lost whole to a full socket receive buffer look like none published, so a node that gets
// no image says how many datagrams the kernel dropped on its sockets (docs/ros2.md, "Socket
// receive buffers"). In process, a camera on a topic nobody publishes: its error names no drops;
// then a loopback socket of the same process is made to overflow, and the error names them.
TEST_F(Live, NoImageNamesTheDatagramsTheKernelDropped) {
  const fs::path dir = dir_;
  const int domain = net_test::loopback_domain(dir);
  one_topic_folder(dir / "f");
  sources::TopicNetwork network(dir / "f");
  net::LiveCamera camera(domain, network, 0, net::LiveSettings{});
  auto error_of_waiting = [&] {
    try {
      camera.wait_frame(0, 0.5);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string dropped = "; the kernel dropped ";
  const std::string quiet = error_of_waiting();
  EXPECT_NE(quiet.find("/cam_1/image_raw: no image within"), std::string::npos) << quiet;
  EXPECT_EQ(quiet.find(dropped), std::string::npos) << quiet;

  net_test::LoopbackUdpPair pair(4096);
  ASSERT_TRUE(pair.ok());
  ASSERT_TRUE(pair.send(200, 1000));
  std::uint64_t drops = 0;  // once the loopback has delivered them
  for (int k = 0; k < 2000 && drops == 0; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    drops = net::udp_drops_of_this_process().value_or(0);
  }
  ASSERT_GT(drops, 0u) << "a 4 KiB buffer held 200 datagrams of 1000 bytes";
  const std::string lost = error_of_waiting();
  EXPECT_NE(lost.find("/cam_1/image_raw: no image within"), std::string::npos) << lost;
  const size_t at = lost.find(dropped);
  ASSERT_NE(at, std::string::npos) << lost;
  EXPECT_GE(std::stoull(lost.substr(at + dropped.size())), drops) << lost;
  EXPECT_NE(lost.find("Socket receive buffers"), std::string::npos) << lost;
}

// A node busy (integrating rounds, or starved of the CPU by a loaded machine) for longer than
// --idle while its camera's images keep coming must take them, not end its stream: the stream is
// silent only when no image has come. Every camera's first image is published and camera 1's
// taken; then, while this test holds the node for idle_s + 1 s, the other five frames come; the
// node must then have all six. (Before, a node that came back after more than idle_s ended its
// stream without looking at what had come.)
TEST_F(Live, ImagesThatCameWhileTheNodeWasBusyAreTaken) {
  const fs::path dir = dir_;
  constexpr int kShort = 6;
  const auto r = net_test::netvmo_bounded(
      "render " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml --frames " +
          std::to_string(kShort) + " --out " + (dir / "ds").string(),
      dir, 120);
  ASSERT_EQ(r.code, 0) << r.err;
  const int domain = net_test::loopback_domain(dir);
  auto ds = sources::open_dataset_source(dir / "ds");
  const int cameras = static_cast<int>(ds->network().cameras.size());
  sources::TopicNetwork network(live_folder(dir / "ds", dir, "live", "", false));
  net::LiveSettings settings;
  settings.idle_s = 0.5;
  // A reader on every camera's topic (the writer waits for them all); camera 1's is the node's.
  std::vector<std::unique_ptr<net::LiveCamera>> live;
  for (int i = 0; i < cameras; ++i)
    live.push_back(std::make_unique<net::LiveCamera>(domain, network, i, settings));
  net::LiveCamera& camera = *live.front();

  // The writer stops after every camera's first image until the node has taken its own.
  std::promise<void> taken;
  std::future<void> go = taken.get_future();
  net::PlaySettings play;
  play.domain = domain;
  play.reliable = true;
  play.wait_readers = 1;
  play.timeout_s = 60.0;
  play.linger_s = 0.5;
  std::string play_error;
  std::thread writer([&] {
    try {
      net::play(*ds, play, [&](int done, int) {
        if (done == cameras) go.wait_for(std::chrono::seconds(60));
      });
    } catch (const std::exception& e) {
      play_error = e.what();
    }
  });
  bool first = false;
  try {
    first = camera.wait_frame(0, 60.0);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  taken.set_value();
  // Busy for longer than idle_s while the other frames come (real time: 5 frames in 0.17 s).
  std::this_thread::sleep_for(std::chrono::duration<double>(settings.idle_s + 1.0));
  writer.join();
  ASSERT_TRUE(play_error.empty()) << play_error;
  ASSERT_TRUE(first);
  EXPECT_TRUE(camera.wait_frame(kShort - 1, 10.0)) << "the stream ended with frames waiting";
  EXPECT_EQ(network.camera_frame_count(0), kShort);
}

// Camera 1 of paper5_render.yaml alone, rendered (kFrames frames) into `dir`/one.
static fs::path one_camera(const fs::path& dir) {
  render::SceneDescription scene =
      io::load_render_scenario(std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml");
  scene.cameras.resize(1);
  scene.edges.clear();
  render::Renderer renderer(scene);
  const fs::path one = dir / "one";
  io::DatasetSettings written;
  written.frames = kFrames;
  written.progress = false;
  io::write_dataset(renderer, one, written);
  return one;
}

// The images of `one` played at --rate 0 (`play_args` added) to a live node of camera 1 of
// `live` (`node_args` added) whose outputs go to logs/out.
static PlayedTo play_to_node(const fs::path& live, const fs::path& one, int domain,
                             const fs::path& logs, const std::string& node_args,
                             const std::string& play_args) {
  return play_to("node " + live.string() + " --camera 1 --live --domain " + std::to_string(domain) +
                     node_args + " --idle 1 --no-plots --out " + (logs / "out").string(),
                 90,
                 one.string() + " --domain " + std::to_string(domain) +
                     " --rate 0 --wait-readers 1 --linger 0.5 --timeout 60 --quiet" + play_args,
                 90, logs);
}

// A node's error says it got no image, and that the kernel dropped datagrams on its sockets.
static bool lost_every_image_to_drops(const std::string& err) {
  return err.find("no image within") != std::string::npos &&
         err.find("; the kernel dropped ") != std::string::npos;
}

// A best-effort reader acknowledges nothing, so `netvmo play` cannot see whether it has an image:
// - The last image. A live node behind on its topic when play deleted its writers right after
//   the last write lost that image: its trace (Cyclone DDS) shows the last image's first 11 of
//   23 datagrams, then the writer's deletion, and nothing more; no socket dropped a datagram.
//   Played as fast as the writers go to a node of a one-camera network, the last of 30 images
//   was lost in 13 of 64 plays without load (and under stress-ng --cpu 4, 3 of 47 runs of
//   PlayedTopicsGiveTheAsyncLaunchsEstimates failed). Play now keeps its writers --linger after
//   the last image when such a reader matches them.
// - The first image. The node's reader takes samples only once it has itself discovered play's
//   writer, which can come after play's side of the match (--wait-readers): the first image was
//   lost in 4 of 40 plays without load, 8 of 40 under stress-ng --cpu 4. Play now waits
//   --settle (0.25 s) after the match when such a reader matches.
// - Any image, when the node's socket receive buffer fills: the kernel drops what arrives, and
//   nothing resends a best-effort datagram. At --rate 0 play writes 30 images (9 MB) in a burst;
//   in a fresh-clone CI run beside other tests, one play lost frames 12 and 13 this way (the
//   node was then given a larger buffer, cyclone_config.cpp). The node counts such drops
//   (node_<id>.json messages.kernel_drops, socket_drops.hpp).
// Here: 24 such plays, best-effort and reliable writers alternately; the node must have every
// frame each time, unless best-effort and the kernel dropped datagrams on its sockets (a node that
// got no image at all then says so in its error line). Without the first wait, the chance that 24
// plays keep every first image is about 0.9^24, under 10 %.
TEST_F(Live, ALiveNodeGetsEveryImageOfAPlay) {
  const fs::path dir = dir_;
  const fs::path one = one_camera(dir), live = live_folder(one, dir, "live_one", "", false);
  const auto ds = sources::open_dataset_source(one);
  const int domain = net_test::loopback_domain(dir);
  for (int k = 0; k < 24; ++k) {
    const fs::path logs = dir / ("run_" + std::to_string(k)), out = logs / "out";
    const auto r = play_to_node(live, one, domain, logs, "", k % 2 ? " --reliable" : "");
    ASSERT_EQ(r.play.code, 0) << r.play.out << r.play.err;
    if (k % 2 == 0 && r.reader.code != 0 && lost_every_image_to_drops(r.reader.err)) {
      std::printf("play %d: no image; %s", k, r.reader.err.c_str());
      continue;
    }
    ASSERT_EQ(r.reader.code, 0) << r.reader.out << r.reader.err;
    // A row per frame (its image time), the first and the last included.
    const auto rows = net_test::read_csv(out / "node_1.csv");
    const auto drops = net_test::read_json(out / "node_1.json").at("messages").at("kernel_drops");
    ASSERT_TRUE(drops.is_number_unsigned()) << "node_1.json: messages.kernel_drops: " << drops;
    const std::string missing = missing_frames(rows, *ds, 0);
    if (k % 2 == 0 && drops.get<std::uint64_t>() > 0) {
      std::printf("play %d: the kernel dropped %llu datagram(s) on the node's sockets; %s\n", k,
                  static_cast<unsigned long long>(drops.get<std::uint64_t>()), missing.c_str());
      continue;
    }
    EXPECT_EQ(missing, "frames without a row:")
        << "play " << k << (k % 2 ? " (reliable writers)" : "") << ", kernel drops " << drops;
  }
}

// What a node says when its socket receive buffer overflows (docs/ros2.md, "Socket receive
// buffers"): every process of the test on netvmo's loopback configuration with a 64 KiB buffer
// (128 KiB as the kernel counts it, under half an image of 23 datagrams), and best-effort plays
// of the 30 images at --rate 0, at most three, until one drops. Either the node gets images: a
// missing frame then needs reported kernel drops, and drops need the warning, naming their number
// (stderr, node_1.json). Or it gets none (a starved node drains its socket too slowly for any
// image to arrive whole, as in a fresh-clone CI run): its one error line must then say that the
// kernel dropped datagrams. Measured 2026-12-06: without load five plays dropped 136-237
// datagrams and kept 5-10 of the 30 frames; under stress-ng --cpu 4 four plays dropped 329-404
// and kept 0-4 (one got no image).
TEST_F(Live, ANodeWhoseSocketBufferOverflowsSaysSo) {
  const fs::path dir = dir_;
  const fs::path one = one_camera(dir), live = live_folder(one, dir, "live_one", "", false);
  const auto ds = sources::open_dataset_source(one);
  test::write_text(
      dir / "small_buffer.xml",
      test::replaced(net::loopback_config_xml(), "<SocketReceiveBufferSize max=\"16MiB\"",
                     "<SocketReceiveBufferSize max=\"64KiB\""));
  net::use_config(dir / "small_buffer.xml");
  const int domain = net::domain_from_pid(::getpid());
  const std::string dropped = "the kernel dropped ";
  int with_drops = 0;
  for (int k = 0; k < 3 && with_drops == 0; ++k) {
    const fs::path logs = dir / ("small_" + std::to_string(k)), out = logs / "out";
    const auto r = play_to_node(live, one, domain, logs, " --timeout 30", "");
    ASSERT_EQ(r.play.code, 0) << r.play.out << r.play.err;
    if (r.reader.code != 0) {  // no image came whole
      test::expect_one_line(r.reader.err, {"/cam_1/image_raw:"});
      EXPECT_TRUE(lost_every_image_to_drops(r.reader.err)) << r.reader.err;
      std::printf("play %d: no image; %s", k, r.reader.err.c_str());
      with_drops += lost_every_image_to_drops(r.reader.err);
      continue;
    }
    const auto j = net_test::read_json(out / "node_1.json");
    const auto drops = j.at("messages").at("kernel_drops");
    ASSERT_TRUE(drops.is_number_unsigned()) << "node_1.json: messages.kernel_drops: " << drops;
    const std::uint64_t n = drops.get<std::uint64_t>();
    const std::string missing = missing_frames(net_test::read_csv(out / "node_1.csv"), *ds, 0);
    std::printf("play %d: %llu datagram(s) dropped; %s\n", k, static_cast<unsigned long long>(n),
                missing.c_str());
    if (missing != "frames without a row:") {
      EXPECT_GT(n, 0u) << "play " << k << ": " << missing;
    }
    const std::string warning = "camera 1: " + dropped + std::to_string(n) + " datagram";
    EXPECT_EQ(j.at("warnings").dump().find(warning) != std::string::npos, n > 0)
        << j.at("warnings").dump();
    EXPECT_EQ(r.reader.err.find(warning) != std::string::npos, n > 0) << r.reader.err;
    EXPECT_NE(r.reader.out.find(std::to_string(n) + " kernel drops"), std::string::npos)
        << r.reader.out;
    with_drops += n > 0;
  }
  EXPECT_EQ(with_drops, 1) << "no play overflowed a 64 KiB buffer";
}
