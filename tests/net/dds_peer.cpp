// A test participant of the estimates topic, in its own process.
//   dds_peer peer  DOMAIN SELF NEIGHBOUR ROUNDS WRITERS OUT   one camera of a two-camera network
//   dds_peer rogue DOMAIN ROUNDS SECONDS                       garbage on the topic
//   dds_peer ros   DOMAIN CAMERA COUNT SECONDS OUT             reads a camera's PoseStamped topic
//     until COUNT samples or SECONDS; OUT: "sec nanosec frame_id px py pz qw qx qy qz" per sample
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
#include <string>

#include "dds_peer_setup.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"

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
  net::RawEstimateWriter w(domain);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 1; k <= rounds; ++k) {
    obs::EstimateMessage m;
    m.initialized = true;
    m.round = static_cast<std::uint64_t>(k);
    m.sender = 0;  // camera 0's id with a NaN position
    m.g_w.translation() = obs::Vec3(nan, 0, 0);
    w.write(m);
    m.sender = 1;  // camera 1's id with a sheared "rotation"
    m.g_w = obs::SE3::Identity();
    m.g_w.linear()(0, 1) = 0.5;
    w.write(m);
    m.sender = 7;  // a camera that is nobody's neighbour, well-formed
    m.g_w = obs::SE3::Identity();
    w.write(m);
  }
  ::usleep(static_cast<useconds_t>(seconds * 1e6));
  return 0;
}
int ros(int domain, int camera, int count, double seconds, const char* out) {
  net::PoseStampedReader reader(domain, camera);
  std::vector<net::PoseStampedSample> all;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const double left =
        seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0 || static_cast<int>(all.size()) >= count) break;
    for (auto& p : reader.take(std::min(left, 0.5))) all.push_back(p);
  }
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 3;
  for (const auto& p : all)
    std::fprintf(f, "%d %u %s %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", p.sec, p.nanosec,
                 p.frame_id.c_str(), p.position.x(), p.position.y(), p.position.z(),
                 p.orientation.w(), p.orientation.x(), p.orientation.y(), p.orientation.z());
  std::fclose(f);
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
      return ros(std::atoi(argv[2]), std::atoi(argv[3]), std::atoi(argv[4]), std::atof(argv[5]),
                 argv[6]);
    if (what == "rogue" && argc == 5)
      return rogue(std::atoi(argv[2]), std::atoi(argv[3]), std::atof(argv[4]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dds_peer: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr,
               "usage: dds_peer peer DOMAIN SELF NEIGHBOUR ROUNDS WRITERS OUT | rogue DOMAIN "
               "ROUNDS SECONDS\n");
  return 64;
}
