// A test participant of the estimate topics, in its own process.
//   dds_peer peer  DOMAIN SELF NEIGHBOUR ROUNDS WRITERS OUT   one camera of a two-camera network
//   dds_peer rogue DOMAIN ROUNDS SECONDS                       garbage on both peers' topics
//   dds_peer writer DOMAIN TOPIC SECDIR IDENTITY SECONDS OUT [LINGER]   a (secured) estimate
//     writer: see writer() below; it stays LINGER seconds after writing OUT
//   dds_peer ros   DOMAIN CAMERA COUNT SECONDS OUT             reads a camera's PoseStamped topic
//     until COUNT samples or SECONDS; OUT: "sec nanosec frame_id px py pz qw qx qy qz" per sample
//   dds_peer tf    DOMAIN CAMERA STATIC COUNT SECONDS OUT      reads rt/tf_static, rt/tf and camera
//     CAMERA's measurement topic until STATIC static and COUNT other transforms (or 3 s without
//     a message after the first transform), or SECONDS; writes OUT.ready once it reads; OUT:
//     "static|tf stamp_ns parent child px py pz qw qx qy qz" per transform and "measurement
//     stamp_ns frame_id px py pz qw qx qy qz c00 c01 ... c55" per measurement
// A peer runs its CameraObserver (pnp error model, a fixed measurement, k_s = 50) for ROUNDS
// lock-step rounds over DdsTransport after WRITERS writers of other participants match (and 0.3 s
// more for their history to arrive), and writes to OUT: one line per accepted message "sender round
// px py pz r00 .. r22", then "final px py pz r00 .. r22", then "refused n0 n1 n2 n3 n4" and "stats
// sent received late foreign".
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "dds_peer_setup.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"
#include "netvmo/pipeline/net/ros_publisher.hpp"

using namespace netvmo;

namespace {
void print_pose(std::FILE* f, const obs::SE3& g) {
  for (int r = 0; r < 3; ++r) std::fprintf(f, " %.17g", g.translation()(r));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) std::fprintf(f, " %.17g", g.linear()(r, c));
}

int peer(int domain, int self, int neighbour, int rounds, int writers, const char* out) {
  obs::CameraObserver cam(self, {neighbour}, net_test::peer_settings());
  net_test::setup_peer(cam);
  net::DdsSettings ds;
  ds.domain = domain;
  ds.timeout_s = 10.0;
  net::DdsTransport t(self, {neighbour}, {10, 11}, ds);
  if (!t.wait_for_writers(writers, 10.0)) {
    std::fprintf(stderr, "peer %d: fewer than %d writers matched\n", self, writers);
    return 2;
  }
  ::usleep(300000);  // a matched writer's history (transient-local) arrives
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 3;
  std::vector<obs::EstimateMessage> inbox;
  for (int k = 0; k < rounds; ++k) {
    t.send(cam.publish(k * net_test::kH));
    t.receive(self, inbox);
    for (const auto& m : inbox)
      if (cam.receive(m) == obs::MessageVerdict::accepted) {
        std::fprintf(f, "%d %llu", m.sender, static_cast<unsigned long long>(m.round));
        print_pose(f, m.g_w);
        std::fprintf(f, "\n");
      }
    cam.step(net_test::kH);
  }
  t.flush(5.0);
  std::fprintf(f, "final");
  print_pose(f, cam.estimate());
  std::fprintf(f, "\nrefused");
  for (auto n : cam.refused()) std::fprintf(f, " %llu", static_cast<unsigned long long>(n));
  const auto& s = t.stats();
  std::fprintf(f, "\nstats %llu %llu %llu %llu\n", static_cast<unsigned long long>(s.sent),
               static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.late),
               static_cast<unsigned long long>(s.foreign));
  std::fclose(f);
  return 0;
}

int rogue(int domain, int rounds, double seconds) {
  // The peers' topics (cameras 10 and 11 at indices 0 and 1).
  net::RawEstimateWriter w0(domain, net::estimate_topic("netvmo_estimates", 10)),
      w1(domain, net::estimate_topic("netvmo_estimates", 11));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 1; k <= rounds; ++k) {
    obs::EstimateMessage m;
    m.initialized = true;
    m.round = static_cast<std::uint64_t>(k);
    m.sender = 0;  // camera 0's index on its topic with a NaN position
    m.g_w.translation() = obs::Vec3(nan, 0, 0);
    w0.write(m);
    m.sender = 1;  // camera 1's index on its topic with a sheared "rotation"
    m.g_w = obs::SE3::Identity();
    m.g_w.linear()(0, 1) = 0.5;
    w1.write(m);
    m.sender = 7;  // another camera's index on both, well-formed
    m.g_w = obs::SE3::Identity();
    w0.write(m);
    w1.write(m);
  }
  ::usleep(static_cast<useconds_t>(seconds * 1e6));
  return 0;
}
int pose_stamped(int domain, int camera, int count, double seconds, const char* out) {
  net::RosTopicReader reader(domain, "rt/netvmo/camera_" + std::to_string(camera) + "/average_pose",
                             ros::pose_stamped_descriptor());
  std::vector<ros::StampedPose> all;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const double left =
        seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0 || static_cast<int>(all.size()) >= count) break;
    for (const auto& m : reader.take(std::min(left, 0.5)))
      all.push_back(ros::decode_pose_stamped(m, "average_pose"));
  }
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 3;
  for (const auto& p : all) {
    const Eigen::Quaterniond q(p.pose.linear());
    std::fprintf(f, "%lld %lld %s %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                 static_cast<long long>(p.stamp_ns / 1000000000),
                 static_cast<long long>(p.stamp_ns % 1000000000), p.frame_id.c_str(),
                 p.pose.translation().x(), p.pose.translation().y(), p.pose.translation().z(),
                 q.w(), q.x(), q.y(), q.z());
  }
  std::fclose(f);
  return 0;
}

void print_ros_pose(std::FILE* f, const obs::SE3& g) {
  const Eigen::Quaterniond q(g.linear());
  std::fprintf(f, " %.17g %.17g %.17g %.17g %.17g %.17g %.17g", g.translation().x(),
               g.translation().y(), g.translation().z(), q.w(), q.x(), q.y(), q.z());
}

int tf(int domain, int camera, int statics, int count, double seconds, const char* out) {
  net::RosTopicReader stat(domain, "rt/tf_static", ros::tf_message_descriptor(), true);
  net::RosTopicReader dyn(domain, "rt/tf", ros::tf_message_descriptor());
  net::RosTopicReader meas(domain, "rt/netvmo/camera_" + std::to_string(camera) + "/measurement",
                           ros::pose_with_covariance_descriptor());
  {  // ready: the test starts the cameras once its readers exist
    std::FILE* r = std::fopen((std::string(out) + ".ready").c_str(), "w");
    if (!r) return 3;
    std::fclose(r);
  }
  std::vector<ros::StampedTransform> s_all, d_all;
  std::vector<ros::StampedPose> m_all;
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0;  // the last message's arrival
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    const double left = seconds - std::chrono::duration<double>(now - t0).count();
    const bool idle = !d_all.empty() && std::chrono::duration<double>(now - last).count() > 3.0;
    if (left <= 0 || (static_cast<int>(s_all.size()) >= statics &&
                      (static_cast<int>(d_all.size()) >= count || idle)))
      break;
    const size_t before = s_all.size() + d_all.size() + m_all.size();
    for (const auto& b : stat.take(0.0))
      for (const auto& t : ros::decode_tf_message(b, "rt/tf_static")) s_all.push_back(t);
    for (const auto& b : meas.take(0.0))
      m_all.push_back(ros::decode_pose_with_covariance(b, "measurement"));
    for (const auto& b : dyn.take(std::min(left, 0.05)))
      for (const auto& t : ros::decode_tf_message(b, "rt/tf")) d_all.push_back(t);
    if (s_all.size() + d_all.size() + m_all.size() > before)
      last = std::chrono::steady_clock::now();
  }
  for (const auto& b : meas.take(0.0))
    m_all.push_back(ros::decode_pose_with_covariance(b, "measurement"));
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 3;
  for (const auto* list : {&s_all, &d_all})
    for (const auto& t : *list) {
      std::fprintf(f, "%s %lld %s %s", list == &s_all ? "static" : "tf",
                   static_cast<long long>(t.stamp_ns), t.parent.c_str(), t.child.c_str());
      print_ros_pose(f, t.pose);
      std::fprintf(f, "\n");
    }
  for (const auto& m : m_all) {
    std::fprintf(f, "measurement %lld %s", static_cast<long long>(m.stamp_ns), m.frame_id.c_str());
    print_ros_pose(f, m.pose);
    for (int k = 0; k < 36; ++k)
      std::fprintf(f, " %.17g", m.covariance ? (*m.covariance)(k / 6, k % 6) : -1.0);
    std::fprintf(f, "\n");
  }
  std::fclose(f);
  return 0;
}
// A writer of estimate topic TOPIC as identity IDENTITY of security folder SECDIR ("-": unsecured):
// OUT gets "refused <why>" when the writer cannot be created, else "matched N" once a reader
// matches (or after SECONDS); a matched writer then writes 5 estimates of camera index 0 at the
// position (kMarker, kMarker, kMarker).
int writer(int domain, const std::string& topic, const std::string& secdir,
           const std::string& identity, double seconds, const char* out, double linger) {
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 3;
  std::optional<net::SecurityIdentity> id;
  if (secdir != "-") id = net::security_identity(secdir, identity);
  std::unique_ptr<net::RawEstimateWriter> w;
  try {
    w = std::make_unique<net::RawEstimateWriter>(domain, topic, id ? &*id : nullptr);
  } catch (const std::runtime_error& e) {
    std::fprintf(f, "refused %s\n", e.what());
    std::fclose(f);
    return 0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (w->matched_readers() == 0 &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < seconds)
    ::usleep(20000);
  const int matched = w->matched_readers();
  if (matched > 0) {
    ::usleep(300000);  // the match on both sides
    for (int k = 1; k <= 5; ++k) {
      obs::EstimateMessage m;
      m.sender = 0;
      m.round = static_cast<std::uint64_t>(k);
      m.initialized = true;
      m.g_w.translation().setConstant(net_test::kMarker);  // looked for in packet captures
      w->write(m);
    }
    ::usleep(500000);  // reliable delivery
  }
  std::fprintf(f, "matched %d\n", matched);
  std::fclose(f);
  // Stays matched (the tests' injected packets need a live writer on the other side).
  if (linger > 0) ::usleep(static_cast<useconds_t>(linger * 1e6));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string what = argc > 1 ? argv[1] : "";
    if (what == "peer" && argc == 8)
      return peer(std::atoi(argv[2]), std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5]),
                  std::atoi(argv[6]), argv[7]);
    if (what == "ros" && argc == 7)
      return pose_stamped(std::atoi(argv[2]), std::atoi(argv[3]), std::atoi(argv[4]),
                          std::atof(argv[5]), argv[6]);
    if (what == "tf" && argc == 8)
      return tf(std::atoi(argv[2]), std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5]),
                std::atof(argv[6]), argv[7]);
    if (what == "writer" && (argc == 8 || argc == 9))
      return writer(std::atoi(argv[2]), argv[3], argv[4], argv[5], std::atof(argv[6]), argv[7],
                    argc == 9 ? std::atof(argv[8]) : 0.0);
    if (what == "rogue" && argc == 5)
      return rogue(std::atoi(argv[2]), std::atoi(argv[3]), std::atof(argv[4]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dds_peer: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr,
               "usage: dds_peer peer DOMAIN SELF NEIGHBOUR ROUNDS WRITERS OUT | rogue DOMAIN "
               "ROUNDS SECONDS | ros DOMAIN CAMERA COUNT SECONDS OUT | tf DOMAIN CAMERA STATIC "
               "COUNT SECONDS OUT | writer DOMAIN TOPIC SECDIR IDENTITY SECONDS OUT\n");
  return 64;
}
