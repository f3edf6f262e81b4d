// DDS Security (docs/processes.md, "Security"): `netvmo security init`'s test PKI with Cyclone
// DDS's authentication, access-control and cryptography plugins. A secured lock-step launch
// equals `netvmo run` bit for bit while a participant without a certificate of the run's CA sees
// nothing; a camera cannot write another camera's estimate topic; a missing security file is one
// line.
#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "dds_peer_setup.hpp"
#include "net_test_util.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"
#include "netvmo/pipeline/net/ros_publisher.hpp"
#include "netvmo/pipeline/net/security.hpp"
#include "netvmo/pipeline/ros/pose_msgs.hpp"

using namespace netvmo;
namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 8;

// A two-camera network 1 - 2 (no images: the PKI needs only the cameras and the graph).
io::NetworkConfig two_cameras() {
  return io::graph_network({1, 2}, {{1, 2}});
}

}  // namespace

// A lock-step launch with every node secured equals `netvmo run` bit for bit; during it, a
// participant with the run's `viewer` certificate (this process) receives camera 1's average pose,
// and an unsecured participant (another process: Cyclone DDS secures a process's
// domain as a whole) receives nothing.
TEST(Security, SecuredLaunchEqualsRunAndStrangersSeeNothing) {
  const fs::path dir = test::scratch_dir("security_launch");
  auto r = net_test::netvmo_bounded("render " + std::string(NETVMO_SOURCE_DIR) +
                                        "/datasets/paper5_render.yaml --frames " +
                                        std::to_string(kFrames) + " --out " + (dir / "ds").string(),
                                    dir, 120);
  ASSERT_EQ(r.code, 0) << r.err;
  r = net_test::netvmo_bounded(
      "security init " + (dir / "sec").string() + " " + (dir / "ds").string(), dir, 60);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  r = net_test::netvmo_bounded(
      "run " + (dir / "ds").string() + " --no-plots --no-overlays --out " + (dir / "run").string(),
      dir, 120);
  ASSERT_EQ(r.code, 0) << r.err;

  const int domain = net_test::loopback_domain(dir);
  const net::SecurityIdentity viewer = net::security_identity(dir / "sec", "viewer");
  net::RosTopicReader seen(domain, "rt/netvmo/camera_1/average_pose",
                           ros::pose_stamped_descriptor(), false, true, &viewer);
  // The stranger listens for as long as the launch may take, then writes what it received.
  const pid_t stranger =
      net::spawn({NETVMO_DDS_PEER, "ros", std::to_string(domain), "1", std::to_string(kFrames),
                  "20", (dir / "stranger.txt").string()},
                 dir / "stranger.log");
  fs::create_directories(dir / "launch_logs");
  r = net_test::netvmo_bounded("launch " + (dir / "ds").string() + " --security " +
                                   (dir / "sec").string() + " --domain " + std::to_string(domain) +
                                   " --no-plots --no-overlays --timeout 90 --out " +
                                   (dir / "launch").string(),
                               dir / "launch_logs", 120);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  std::vector<std::vector<std::uint8_t>> seen_msgs;
  for (int k = 0; k < 20 && static_cast<int>(seen_msgs.size()) < kFrames; ++k)
    for (auto& m : seen.take(0.5)) seen_msgs.push_back(std::move(m));
  const auto s = net::supervise({stranger}, 40.0, false);
  ASSERT_TRUE(s[0].finished && s[0].exit_code == 0) << test::slurp(dir / "stranger.log");
  EXPECT_EQ(test::slurp(dir / "launch" / "estimates.csv"),
            test::slurp(dir / "run" / "estimates.csv"));
  // The viewer matches once its handshake with camera 1's node is done (the node does not wait
  // for it): the later frames' poses, each the node's estimate of its frame.
  EXPECT_GE(seen_msgs.size(), 1u);
  const auto rows = net_test::read_csv(dir / "launch" / "nodes" / "node_1.csv");
  ASSERT_EQ(rows.size(), static_cast<size_t>(kFrames + 1));
  for (const auto& m : seen_msgs) {
    const auto p = ros::decode_pose_stamped(m, "average_pose");
    const int k = static_cast<int>(std::llround(p.stamp_ns * 1e-9 * 30));  // paper5: 30 fps
    ASSERT_TRUE(k >= 0 && k < kFrames) << p.stamp_ns;
    const obs::SE3 est = net_test::pose_at(rows[static_cast<size_t>(k) + 1], 38);  // est_w
    EXPECT_LE((p.pose.translation() - est.translation()).norm(), 1e-12) << "frame " << k;
  }
  EXPECT_EQ(test::slurp(dir / "stranger.txt"), "");  // one line per received pose
  fs::remove_all(dir);
}

// Access control and authentication on the estimate topics of a two-camera network, each
// participant a process of its own: camera 2's secured transport (this process) reads camera 1's
// topic; camera 1's certificate may write it (the control: its 5 messages arrive), camera 2's may
// not (its writer is refused), and neither an unsecured writer nor one certified by another CA
// ever matches camera 2's reader.
TEST(Security, ACameraWritesOnlyItsOwnTopicAndStrangersNone) {
  const fs::path dir = test::scratch_dir("security_acl");
  const auto net = two_cameras();
  net::write_test_pki(dir / "sec", net);
  net::write_test_pki(dir / "other", net);  // another PKI: its certificates are strangers here
  const int domain = net_test::loopback_domain(dir);
  net::DdsSettings ds;
  ds.domain = domain;
  ds.mode = net::Mode::async;
  ds.security = net::security_identity(dir / "sec", net::camera_identity(2));
  net::DdsTransport camera2(1, {0}, {1, 2}, ds);
  const std::string topic1 = net::estimate_topic("netvmo_estimates", 1);
  const auto writer = [&](const std::string& name, const std::string& secdir,
                          const std::string& identity, const std::string& seconds) {
    return std::vector<std::string>{
        NETVMO_DDS_PEER, "writer", std::to_string(domain),          topic1, secdir,
        identity,        seconds,  (dir / (name + ".txt")).string()};
  };
  const auto res = net_test::run_all(
      {writer("own", (dir / "sec").string(), "cam_1", "30"),
       writer("wrong", (dir / "sec").string(), "cam_2", "30"), writer("unsecured", "-", "-", "8"),
       writer("foreign_ca", (dir / "other").string(), "cam_1", "8")},
      dir, 60.0);
  for (size_t k = 0; k < res.size(); ++k)
    ASSERT_TRUE(res[k].finished && res[k].exit_code == 0)
        << "writer " << k << ": " << test::slurp(dir / ("child_" + std::to_string(k) + ".log"));
  EXPECT_EQ(test::slurp(dir / "own.txt"), "matched 1\n");
  EXPECT_EQ(test::slurp(dir / "wrong.txt")
                .rfind("refused Cyclone DDS: create writer: Not Allowed "
                       "By Security",
                       0),
            0u)
      << test::slurp(dir / "wrong.txt");
  EXPECT_EQ(test::slurp(dir / "unsecured.txt"), "matched 0\n");
  EXPECT_EQ(test::slurp(dir / "foreign_ca.txt"), "matched 0\n");
  std::vector<obs::EstimateMessage> inbox, all;
  for (int k = 0; k < 50 && all.size() < 5; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    camera2.receive(1, inbox);
    all.insert(all.end(), inbox.begin(), inbox.end());
  }
  EXPECT_EQ(all.size(), 5u);  // camera 1's, from its own certificate only
  EXPECT_EQ(camera2.stats().received, 5u);
  fs::remove_all(dir);
}

namespace {

// Every frame seen on the loopback interface while it runs (as root; AF_PACKET).
class LoopbackCapture {
 public:
  /// Starts capturing; `why_not` says why it cannot (not root, no AF_PACKET).
  bool start(std::string& why_not) {
    fd_ = ::socket(AF_PACKET, SOCK_RAW, htons(ETH_P_ALL));
    if (fd_ < 0) {
      why_not =
          std::string("no raw socket on lo (") + std::strerror(errno) + "): the capture needs root";
      return false;
    }
    sockaddr_ll a{};
    a.sll_family = AF_PACKET;
    a.sll_protocol = htons(ETH_P_ALL);
    a.sll_ifindex = static_cast<int>(::if_nametoindex("lo"));
    timeval tv{0, 50000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    if (a.sll_ifindex == 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      why_not = std::string("cannot bind a raw socket to lo: ") + std::strerror(errno);
      return false;
    }
    thread_ = std::thread([this] {
      std::vector<char> buf(1 << 16);
      while (!stop_) {
        const ssize_t n = ::recv(fd_, buf.data(), buf.size(), 0);
        if (n > 0) bytes_.append(buf.data(), static_cast<size_t>(n));
      }
    });
    return true;
  }
  /// Stops; everything captured.
  std::string finish() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return bytes_;
  }
  ~LoopbackCapture() {
    finish();
    if (fd_ >= 0) ::close(fd_);
  }

 private:
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::string bytes_;
};

// Camera 1's 5 estimates, at position kMarker, to camera 2's transport on `domain` (secured
// with `sec`'s identities when not empty), captured on lo. Returns the capture; `received`: the
// estimates camera 2 took.
std::string captured_exchange(const fs::path& dir, int domain, const fs::path& sec,
                              size_t& received) {
  LoopbackCapture capture;
  std::string why_not;
  if (!capture.start(why_not)) throw std::runtime_error(why_not);
  net::DdsSettings ds;
  ds.domain = domain;
  ds.mode = net::Mode::async;
  if (!sec.empty()) ds.security = net::security_identity(sec, net::camera_identity(2));
  net::DdsTransport camera2(1, {0}, {1, 2}, ds);
  const auto res = net_test::run_all(
      {{NETVMO_DDS_PEER, "writer", std::to_string(domain),
        net::estimate_topic("netvmo_estimates", 1), sec.empty() ? "-" : sec.string(), "cam_1", "30",
        (dir / "writer.txt").string()}},
      dir, 60.0);
  EXPECT_TRUE(res[0].finished && res[0].exit_code == 0) << test::slurp(dir / "child_0.log");
  std::vector<obs::EstimateMessage> inbox;
  received = 0;
  for (int k = 0; k < 50 && received < 5; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    camera2.receive(1, inbox);
    received += inbox.size();
  }
  return capture.finish();
}

}  // namespace

// Encrypted data: the same exchange captured on the loopback interface carries camera 1's
// position in clear without security (the control: the capture sees the payload) and nowhere in
// a secured run (the governance encrypts data, metadata and discovery). Skipped, saying why,
// where a raw socket is not allowed (not root).
TEST(Security, ASecuredExchangeCarriesNoPoseInClear) {
  const fs::path dir = test::scratch_dir("security_capture");
  {
    LoopbackCapture probe;
    std::string why_not;
    if (!probe.start(why_not)) GTEST_SKIP() << why_not;
  }
  net::write_test_pki(dir / "sec", two_cameras());
  const int domain = net_test::loopback_domain(dir);
  char marker[sizeof(double)];
  std::memcpy(marker, &net_test::kMarker, sizeof marker);
  const std::string needle(marker, sizeof marker);
  size_t received = 0;
  // Two domains: Cyclone DDS secures a process's domain as a whole.
  const std::string clear = captured_exchange(dir, domain, {}, received);
  EXPECT_EQ(received, 5u);
  EXPECT_NE(clear.find(needle), std::string::npos) << clear.size() << " bytes captured";
  const std::string secured = captured_exchange(dir, domain + 1, dir / "sec", received);
  EXPECT_EQ(received, 5u);
  EXPECT_GT(secured.size(), 0u);
  EXPECT_EQ(secured.find(needle), std::string::npos);
  std::printf("captured %zu bytes unsecured, %zu secured\n", clear.size(), secured.size());
  fs::remove_all(dir);
}

TEST(Security, AMissingSecurityFileIsOneLine) {
  const fs::path dir = test::scratch_dir("security_missing");
  net::write_test_pki(dir / "sec", two_cameras());
  fs::remove(dir / "sec" / "cam_2.permissions.p7s");
  test::expect_input_error([&] { net::security_identity(dir / "sec", net::camera_identity(2)); },
                           {"cam_2.permissions.p7s: not found", "netvmo security init"});
  EXPECT_NO_THROW(net::security_identity(dir / "sec", net::camera_identity(1)));
  fs::remove_all(dir);
}
