// Several machines, emulated (docs/processes.md, "Several machines, emulated"): every node in a
// network namespace of its own behind a bridge (tools/netns_run.sh), configured from
// datasets/cyclonedds_multihost.template.xml, loss and partitions made by nftables in the kernel,
// the nodes' files gathered and merged with `netvmo merge`. Skipped, with the reason, where this
// machine does not allow network namespaces (not root).
#include <sys/wait.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "net_test_util.hpp"

using namespace netvmo;
namespace fs = std::filesystem;

namespace {

// tools/netns_run.sh on `dataset` into `out` (bounded); its exit code, stderr in `err`.
int netns_run(const fs::path& dataset, const fs::path& out, const std::string& args,
              std::string& err) {
  const fs::path log = out.string() + ".stderr";
  const std::string cmd = "timeout -k 5 150 bash " + std::string(NETVMO_SOURCE_DIR) +
                          "/tools/netns_run.sh " + std::string(NETVMO_BINARY_DIR) + "/netvmo " +
                          dataset.string() + " " + out.string() + " " + args + " > " +
                          out.string() + ".stdout 2> " + log.string();
  const int status = std::system(cmd.c_str());
  err = test::slurp(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path render(const fs::path& dir, int frames) {
  const auto r = net_test::netvmo_bounded(
      "render " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml --frames " +
          std::to_string(frames) + " --out " + (dir / "ds").string(),
      dir, 120);
  EXPECT_EQ(r.code, 0) << r.err;
  return dir / "ds";
}

// Every camera's networked estimate ends within 1 cm and 1 degree of g* (the async bound,
// docs/processes.md).
void expect_converged(const fs::path& summary_file) {
  const auto summary = net_test::read_json(summary_file);
  for (const auto& c : summary["cameras"]) {
    const auto& e = c["networked"]["vs_g_star"];
    ASSERT_FALSE(e.is_null());
    EXPECT_LT(e["final_position_m"].get<double>(), 0.01) << "camera " << c["id"];
    EXPECT_LT(e["final_orientation_deg"].get<double>(), 1.0) << "camera " << c["id"];
  }
}

// node_<id>_links.csv: the neighbours in the mutual term after each frame.
std::vector<std::string> links(const fs::path& nodes, int camera) {
  std::vector<std::string> out;
  const auto rows = net_test::read_csv(nodes / ("node_" + std::to_string(camera) + "_links.csv"));
  for (size_t r = 1; r < rows.size(); ++r) out.push_back(rows[r].size() > 2 ? rows[r][2] : "");
  return out;
}

}  // namespace

// Lock-step across namespaces, over the bridge, equals `netvmo run` byte for byte.
TEST(NetNs, LockStepAcrossNamespacesEqualsRun) {
  const fs::path dir = test::scratch_dir("netns_lockstep");
  const fs::path ds = render(dir, 8);
  std::string err;
  const int code = netns_run(ds, dir / "ns", "--timeout 100 -- --frames 8", err);
  if (code == 77) GTEST_SKIP() << err;
  ASSERT_EQ(code, 0) << err;
  const auto r = net_test::netvmo_bounded(
      "run " + ds.string() + " --no-plots --no-overlays --out " + (dir / "run").string(), dir, 120);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(test::slurp(dir / "ns" / "merged" / "estimates.csv"),
            test::slurp(dir / "run" / "estimates.csv"));
  EXPECT_EQ(test::slurp(dir / "ns" / "merged" / "errors.csv"),
            test::slurp(dir / "run" / "errors.csv"));
}

// Async with 10 % of every namespace's incoming packets dropped by nftables: reliable DDS
// retransmits, and every camera ends within the async bound; the kernel dropped 10 % +- 4 %.
// Retransmissions delay messages, and delays slow the settling (docs/processes.md, "Why the same
// 1 cm / 1° bound holds"), more so on a loaded machine (one run of 30 frames beside a build
// ended 12.9 mm from g*): 60 frames, 2 s of camera time, as the async faults test runs. Every
// node starts at the common start, frame 0: a lost discovery message is sent again seconds later
// (8.1 s in 1 of 41 runs), and with a start fixed ahead of time two nodes joined at frame 42 and
// the network ended 54-62 mm from g*; the harness now starts once every node is ready.
TEST(NetNs, AsyncConvergesUnderTenPercentKernelLoss) {
  const fs::path dir = test::scratch_dir("netns_loss");
  const fs::path ds = render(dir, 60);
  std::string err;
  const int code = netns_run(
      ds, dir / "ns", "--mode async --loss 10 --timeout 100 -- --ke 10 --ks 100 --speed 0.25", err);
  if (code == 77) GTEST_SKIP() << err;
  ASSERT_EQ(code, 0) << err;
  for (int c = 1; c <= 5; ++c) {
    const auto node =
        net_test::read_json(dir / "ns" / "nodes" / ("node_" + std::to_string(c) + ".json"));
    EXPECT_EQ(node["first_frame"].get<int>(), 0)
        << "camera " << c << " joined late (discovery " << node["timing"]["discovery_s"] << " s)";
  }
  expect_converged(dir / "ns" / "merged" / "summary.json");
  std::ifstream in(dir / "ns" / "loss.txt");
  int id = 0, cameras = 0;
  double packets = 0, dropped = 0;
  while (in >> id >> packets >> dropped) {
    ++cameras;
    ASSERT_GT(packets, 100) << "camera " << id;
    EXPECT_NEAR(dropped / packets, 0.10, 0.04)
        << "camera " << id << ": " << dropped << " of " << packets;
  }
  EXPECT_EQ(cameras, 5);
}

// Clocks that disagree across namespaces (docs/processes.md, "Clocks that disagree"): camera 2's
// node runs 40 ms ahead, camera 3's 40 ms behind, camera 4's 2 s ahead. The merge of the gathered
// node files finds each offset within its bound (below half a frame) of the injected one, and
// async converges.
TEST(NetNs, ClocksThatDisagreeAreMeasuredAcrossNamespaces) {
  const fs::path dir = test::scratch_dir("netns_clocks");
  const fs::path ds = render(dir, 30);
  std::string err;
  const int code = netns_run(ds, dir / "ns",
                             "--mode async --clock-offsets 2:0.04,3:-0.04,4:2 --timeout 100 -- "
                             "--ke 10 --ks 100 --speed 0.25",
                             err);
  if (code == 77) GTEST_SKIP() << err;
  ASSERT_EQ(code, 0) << err;
  expect_converged(dir / "ns" / "merged" / "summary.json");
  const std::map<int, double> injected = {{1, 0.0}, {2, 0.04}, {3, -0.04}, {4, 2.0}, {5, 0.0}};
  const auto clocks = net_test::read_json(dir / "ns" / "merged" / "clocks.json");
  int cameras = 0;
  for (const auto& c : clocks["cameras"]) {
    const int id = c["camera"].get<int>();
    ASSERT_FALSE(c["offset_s"].is_null()) << "camera " << id;
    const double b = c["bound_s"].get<double>();
    EXPECT_LE(std::abs(c["offset_s"].get<double>() - injected.at(id)), b + 1e-9) << "camera " << id;
    EXPECT_LT(b, 0.5 / 30.0) << "camera " << id;
    ++cameras;
  }
  EXPECT_EQ(cameras, 5);
}

// A partition: the bridge forwards nothing to or from camera 4 (neighbours 3 and 5) from 1.5 s
// to 3.5 s of wall time after the common start (camera time 0.375 s to 0.875 s at --speed 0.25,
// frames ~11 to ~26). Past the staleness bound (0.25 s, 7.5 frames) cameras 3 and 5 drop camera
// 4 from their mutual terms and camera 4 drops both; with the link back, each is heard again and
// re-admitted; the network then converges within the async bound. The frames are those of the
// cut's and the heal's times as the harness recorded them once nftables had them (events.txt):
// on a loaded machine the four nft calls that make the cut start it late (frame 22 of the plan
// was after the heal's readmission in one run with both cores three times oversubscribed).
TEST(NetNs, APartitionIsForgottenAndReadmitted) {
  const fs::path dir = test::scratch_dir("netns_cut");
  const fs::path ds = render(dir, 60);
  std::string err;
  const int code = netns_run(ds, dir / "ns",
                             "--mode async --cut 4@1.5:2 --timeout 100 -- --ke 10 --ks 100 "
                             "--speed 0.25",
                             err);
  if (code == 77) GTEST_SKIP() << err;
  ASSERT_EQ(code, 0) << err;
  const fs::path nodes = dir / "ns" / "nodes";
  const auto l3 = links(nodes, 3), l4 = links(nodes, 4), l5 = links(nodes, 5);
  ASSERT_EQ(l4.size(), 60u);
  const auto has = [](const std::string& set, const std::string& id) {
    std::istringstream s(set);
    std::string x;
    while (s >> x)
      if (x == id) return true;
    return false;
  };
  // The frames (30 fps at --speed 0.25: 7.5 a second of wall time) of the cut and the heal.
  std::map<std::string, double> at;
  {
    std::ifstream in(dir / "ns" / "events.txt");
    for (std::string line; std::getline(in, line);) {
      std::istringstream f(line);
      std::string what, x;
      f >> what;
      if (what != "start") f >> x;  // the camera's id
      f >> at[what];
    }
  }
  ASSERT_EQ(at.size(), 3u) << "events.txt: start, cut and healed";
  const double cut_frame = (at["cut"] - at["start"]) * 7.5,
               heal_frame = (at["healed"] - at["start"]) * 7.5, bound_frames = 7.5;
  std::printf("cut at frame %.1f, healed at frame %.1f\n", cut_frame, heal_frame);
  ASSERT_GT(cut_frame, 6.0) << "the cut started before frame 5's check";
  ASSERT_GT(heal_frame - cut_frame, bound_frames + 2.0) << "cut too short to pass the bound";
  // Before the cut, in the middle of its part past the bound (both sides), and at the end.
  const auto mid = static_cast<size_t>(std::lround(0.5 * (cut_frame + bound_frames + heal_frame)));
  ASSERT_LT(mid + 1, l4.size());
  for (const auto* l : {&l3, &l5}) {
    EXPECT_TRUE(has((*l)[5], "4"));
    EXPECT_FALSE(has((*l)[mid], "4")) << "frame " << mid;
    EXPECT_TRUE(has(l->back(), "4"));
  }
  EXPECT_EQ(l4[5], "3 5");
  EXPECT_EQ(l4[mid], "") << "frame " << mid;
  EXPECT_EQ(l4.back(), "3 5");
  for (int id : {3, 4, 5})
    EXPECT_GE(net_test::read_json(
                  nodes / ("node_" + std::to_string(id) + ".json"))["messages"]["forgotten_stale"]
                  .get<int>(),
              1)
        << "camera " << id;
  expect_converged(dir / "ns" / "merged" / "summary.json");
}

// Kernel delay and jitter where the kernel has netem (50 ms +- 10 ms on every namespace's
// outgoing packets): async still converges within its bound. Skipped, with the reason, where
// netem is missing (this project's machines: "Specified qdisc kind is unknown"); the
// receiver-side --delay covers delay there (Async.*).
TEST(NetNs, AsyncConvergesUnderKernelDelayAndJitter) {
  const fs::path dir = test::scratch_dir("netns_delay");
  const fs::path ds = render(dir, 60);
  std::string err;
  const int code = netns_run(ds, dir / "ns",
                             "--mode async --delay 50:10 --timeout 100 -- --ke 10 --ks 100 "
                             "--speed 0.25",
                             err);
  if (code == 77) GTEST_SKIP() << err;
  ASSERT_EQ(code, 0) << err;
  expect_converged(dir / "ns" / "merged" / "summary.json");
}

namespace {

// The network namespaces of the harness run by process `pid` (named nv<pid>...).
std::vector<std::string> namespaces_of(pid_t pid) {
  std::vector<std::string> out;
  if (!fs::is_directory("/var/run/netns")) return out;
  const std::string prefix = "nv" + std::to_string(pid);
  for (const auto& e : fs::directory_iterator("/var/run/netns")) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 &&
        !std::isdigit(static_cast<unsigned char>(name[prefix.size()])))
      out.push_back(name);
  }
  return out;
}

}  // namespace

// Every path removes the harness's namespaces and the nodes in them: an error after they were
// made (a --cut naming no camera) and a SIGTERM in mid-run.
TEST(NetNs, EveryPathRemovesItsNamespaces) {
  const fs::path dir = test::scratch_dir("netns_cleanup");
  const fs::path ds = render(dir, 60);
  const std::string script = std::string(NETVMO_SOURCE_DIR) + "/tools/netns_run.sh";
  const std::string exe = std::string(NETVMO_BINARY_DIR) + "/netvmo";
  {
    const pid_t p = net::spawn({"/bin/bash", script, exe, ds.string(), (dir / "a").string(),
                                "--mode", "async", "--cut", "9@1:1", "--", "--speed", "0.25"},
                               dir / "a.log");
    const auto r = net::supervise({p}, 60.0, true);
    if (r[0].finished && r[0].exit_code == 77) GTEST_SKIP() << test::slurp(dir / "a.log");
    EXPECT_TRUE(r[0].finished && r[0].exit_code == 2) << test::slurp(dir / "a.log");
    EXPECT_NE(test::slurp(dir / "a.log").find("--cut 9@1:1: no camera 9"), std::string::npos);
    EXPECT_TRUE(namespaces_of(p).empty());
  }
  {
    const pid_t p = net::spawn({"/bin/bash", script, exe, ds.string(), (dir / "b").string(),
                                "--mode", "async", "--", "--speed", "0.25"},
                               dir / "b.log");
    // Once every camera's namespace exists and its node runs (its log has its first line).
    bool running = false;
    for (int k = 0; k < 300 && !running; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      running = namespaces_of(p).size() >= 6 &&  // the bridge's and the five cameras'
                !test::slurp(dir / "b" / "node_5.log").empty();
    }
    ASSERT_TRUE(running) << test::slurp(dir / "b.log");
    ::kill(p, SIGTERM);
    const auto r = net::supervise({p}, 30.0, true);
    EXPECT_TRUE(r[0].finished) << net::describe(r[0]);
    EXPECT_TRUE(namespaces_of(p).empty());
    // No node of this dataset left running.
    const std::string left = "pgrep -f '[n]etvmo node " + ds.string() + " ' > /dev/null";
    EXPECT_NE(std::system(left.c_str()), 0) << "a node of the harness still runs";
  }
}
