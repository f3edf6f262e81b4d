// Output folders under adverse conditions, with the netvmo binary: a second command writing the
// same folder, an output folder that is (or holds, or lies in) the dataset, absurd numbers,
// cameras whose video cannot be read (--keep-going), and SIGKILL at random points of run,
// render and node (crash safety). Every child process is bounded in time.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "netvmo/pipeline/io/output_dir.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const std::string kNetvmo = std::string(NETVMO_BINARY_DIR) + "/netvmo";
const std::string kScenario = std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml";

int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// Every file under dir (relative path -> content), folders as entries with content "<dir>".
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> m;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(e.path(), dir).string();
    m[rel] = e.is_directory() ? std::string("<dir>") : test::slurp(e.path());
  }
  return m;
}

// The names in dir's parent that start with dir's name.
std::vector<std::string> siblings(const fs::path& dir) {
  std::vector<std::string> v;
  const std::string name = dir.filename().string();
  for (const auto& e : fs::directory_iterator(dir.parent_path())) {
    const std::string n = e.path().filename().string();
    if (n.rfind(name, 0) == 0) v.push_back(n);
  }
  std::sort(v.begin(), v.end());
  return v;
}

// Starts argv with output to `log`; returns its pid.
pid_t start(const std::vector<std::string>& argv, const fs::path& log) {
  std::fflush(stdout);  // the child would write this process's buffered output again
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (f) ::dup2(::fileno(stdout), 2);
    std::vector<char*> a;
    for (const auto& s : argv) a.push_back(const_cast<char*>(s.c_str()));
    a.push_back(nullptr);
    ::execv(a[0], a.data());
    ::_exit(127);
  }
  return pid;
}

// Waits for pid at most `seconds`, then kills it (SIGKILL); returns the wait status.
int wait_bounded(pid_t pid, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  while (Clock::now() < end) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return status;
}

// Lines of s that contain `word` (stderr also carries the progress bar).
int count_lines_with(const std::string& s, const std::string& word) {
  std::istringstream in(s);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.find(word) != std::string::npos;
  return n;
}

int dds_domain() {
  return 1 + static_cast<int>(::getpid() % 200);
}

// ---------------------------------------------------------------------------------------------

TEST(OutputSafety, ASecondCommandOnTheSameOutputFailsPlainly) {
  const auto dir = testing::fresh_dir("lock");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(3, 20));
  const fs::path out = dir / "out";
  // Two real runs at once: the first holds the lock while it works. It is stopped (SIGSTOP)
  // once its staging folder exists, so that it still holds the lock however fast this machine
  // runs it, and continued after the second has tried.
  const pid_t first =
      start({kNetvmo, "run", (dir / "ds").string(), "--out", out.string()}, dir / "first.log");
  const fs::path staging = dir / ("out.partial-" + std::to_string(first));
  const auto until = Clock::now() + std::chrono::seconds(60);
  while (!fs::exists(staging) && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_EQ(::kill(first, SIGSTOP), 0);
  const bool holding = fs::exists(staging);
  const auto second = test::run_netvmo(
      "run " + (dir / "ds").string() + " --out " + out.string() + " --no-overlays --no-plots", dir,
      60);
  ASSERT_EQ(::kill(first, SIGCONT), 0);
  const int status = wait_bounded(first, 60);
  ASSERT_TRUE(holding) << "the first run ended before it could be stopped";
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::slurp(dir / "first.log");
  EXPECT_EQ(second.code, 1);
  EXPECT_EQ(count_lines(second.err), 1) << second.err;
  EXPECT_NE(second.err.find("another netvmo run (pid " + std::to_string(first) + ") is writing " +
                            out.string()),
            std::string::npos)
      << second.err;
  EXPECT_TRUE(fs::exists(out / "summary.json"));  // the first run's result, complete

  // Every command that writes an output folder takes the same lock (held here by this test).
  const auto held = std::make_unique<io::OutputDir>(dir / "held", "render");
  const std::string d = (dir / "ds").string(), h = (dir / "held").string();
  for (const std::string& args :
       {"render " + kScenario + " --out " + h + " --frames 1", "detect " + d + " --out " + h,
        "run " + d + " --out " + h, "launch " + d + " --out " + h,
        "node " + d + " --camera 1 --domain 3 --out " + h, "demo --out " + h + " --frames 1"}) {
    const auto r = test::run_netvmo(args, dir, 60);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << args << ": one line: " << r.err;
    EXPECT_NE(r.err.find("another netvmo render (pid " + std::to_string(::getpid()) +
                         ") is writing " + h),
              std::string::npos)
        << args << ": " << r.err;
  }
}

// Every path a command prints names what is there when it has ended: the demo, run and sweep
// build their output in a temporary sibling, but print (and record in summary.json) the final
// names.
TEST(OutputSafety, PrintedPathsExistWhenTheCommandEnds) {
  const auto dir = testing::fresh_dir("printed_paths");
  // The number of paths printed under dir, each of which must exist.
  const auto check = [&](const test::CliResult& c, const std::string& what) {
    EXPECT_EQ(c.code, 0) << what << ": " << c.err;
    EXPECT_EQ(c.out.find(".partial"), std::string::npos) << what << ": " << c.out;
    int paths = 0;
    std::istringstream words(c.out);
    for (std::string w; words >> w;) {
      if (w.rfind(dir.string(), 0) != 0) continue;
      while (!w.empty() && (w.back() == ':' || w.back() == ',' || w.back() == '/')) w.pop_back();
      EXPECT_TRUE(fs::exists(w)) << what << " printed " << w << " which does not exist";
      ++paths;
    }
    return paths;
  };
  const fs::path demo = dir / "demo";
  auto c = test::run_netvmo("demo --out " + demo.string() + " --frames 3", dir, 300);
  EXPECT_GE(check(c, "demo"), 6) << c.out;  // dataset (3 times), results, mosaic and two plots
  EXPECT_NE(c.out.find((demo / "dataset").string() + ": 3 frames"), std::string::npos) << c.out;
  const auto s = nlohmann::json::parse(test::slurp(demo / "summary.json"));
  EXPECT_EQ(s["dataset"].get<std::string>(), (demo / "dataset").string());
  c = test::run_netvmo("run " + (demo / "dataset").string() + " --out " + (dir / "run").string(),
                       dir, 300);
  EXPECT_GE(check(c, "run"), 1) << c.out;
  for (int i = 0; i < 2; ++i) {  // detected, then reused from the previous result
    c = test::run_netvmo(
        "sweep " + (demo / "dataset").string() + " --out " + (dir / "sweep").string() + " --ks 50",
        dir, 300);
    EXPECT_GE(check(c, "sweep"), 2) << c.out;
  }
  EXPECT_NE(c.out.find("reusing " + (dir / "sweep" / "inputs.csv").string()), std::string::npos)
      << c.out;
}

TEST(OutputSafety, TheOutputFolderMayNotBeOrHoldOrLieInTheDataset) {
  const auto dir = testing::fresh_dir("apart");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 3));
  const auto before = snapshot(dir / "ds");
  const std::string d = (dir / "ds").string();
  struct Case {
    std::string args, needle;
  };
  const std::vector<Case> cases = {
      {"run " + d + " --out " + d, "is the dataset folder"},
      {"run " + d + " --out " + d + "/", "is the dataset folder"},
      {"run " + d + " --out " + d + "/results", "lies inside the dataset folder"},
      {"run " + d + " --out " + dir.string(), "lies inside --out"},
      {"detect " + d + " --out " + d, "is the dataset folder"},
      {"launch " + d + " --out " + d, "is the dataset folder"},
      // merge replaces --out whole: it may not hold (or be) the node outputs it reads.
      {"merge " + (dir / "m" / "nodes").string() + " --dataset " + d + " --out " +
           (dir / "m").string(),
       "the NODES folder " + (dir / "m" / "nodes").string() + " lies inside --out"},
      {"merge " + (dir / "m").string() + " --dataset " + d + " --out " + (dir / "m").string(),
       "is the NODES folder"},
      {"node " + d + " --camera 1 --domain 3 --out " + d + "/n", "lies inside the dataset"},
      {"render " + kScenario + " --out " + d + "/again --frames 1", "lies inside the dataset"},
      // A recorded dataset (not written by netvmo render) is never replaced.
      {"render " + kScenario + " --out " + d + " --frames 1", "was not written by netvmo"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_netvmo(c.args, dir, 60);
    EXPECT_EQ(r.code, 1) << c.args;
    EXPECT_EQ(count_lines(r.err), 1) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << c.args << ": " << r.err;
  }
  EXPECT_EQ(snapshot(dir / "ds"), before) << "the dataset is untouched";
}

TEST(OutputSafety, AbsurdNumbersAreRejectedWithTheirRange) {
  const auto dir = testing::fresh_dir("limits");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(3, 3));
  const std::string d = (dir / "ds").string(), o = " --out " + (dir / "o").string();
  struct Case {
    std::string args;
    std::vector<std::string> needles;
  };
  const std::vector<Case> cases = {
      // Rounds: the limit, and the stable range of this dataset (d_max = 2, 30 frames/s,
      // k_e + 2 k_s d_max = 201: N >= 7 keeps the step factor <= 1, N < 4 passes 2).
      {"run " + d + o + " --rounds 1000000000",
       {"--rounds 1000000000", "at most 10000", "N >= 7", "N < 4"}},
      {"run " + d + o + " --ke 1e9", {"--ke/--ks", "more than 10000"}},
      {"run " + d + o + " --ks nan", {"--ks"}},
      {"launch " + d + o + " --rounds 20000", {"--rounds 20000", "at most 10000"}},
      {"node " + d + " --camera 1 --domain 3 --out " + (dir / "n").string() + " --rounds 20000",
       {"--rounds 20000"}},
      {"simulate " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5.yaml" + o +
           " --duration 1e9",
       {"--duration", "3600"}},
      {"simulate " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5.yaml" + o + " --ks 1e9",
       {"--ke/--ks"}},
      {"render " + kScenario + o + " --frames 1000000000", {"--frames"}},
      {"render " + kScenario + o + " --spp 100000", {"--spp"}},
      {"demo" + o + " --frames 1000000000", {"--frames"}},
      {"bench --frames 1000000000", {"--frames"}},
      {"launch " + d + o + " --delay 1e9", {"--delay"}},
      {"launch " + d + o + " --speed 1e-9", {"--speed"}},
      {"launch " + d + o + " --timeout 1e12", {"--timeout"}},
      {"node " + d + " --camera 1 --domain 3 --out " + (dir / "n").string() + " --timeout 1e12",
       {"--timeout"}},
      {"detect " + d + o + " --max-hamming 40", {"--max-hamming"}},
      {"detect " + d + o + " --threads 100000", {"--threads"}},
  };
  for (const auto& c : cases) {
    const auto t0 = Clock::now();
    const auto r = test::run_netvmo(c.args, dir, 60);
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 30.0) << c.args;
    for (const auto& n : c.needles) EXPECT_NE(r.err.find(n), std::string::npos) << c.args << r.err;
    EXPECT_FALSE(fs::exists(dir / "o")) << c.args << ": nothing written";
  }
}

// ---------------------------------------------------------------------------------------------
// --keep-going and videos that cannot be read.

struct OwnClockRecord {
  int frame, camera, delta;
};
std::vector<OwnClockRecord> read_estimates(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<OwnClockRecord> v;
  while (std::getline(in, line)) {
    OwnClockRecord r{};
    double t;
    if (std::sscanf(line.c_str(), "%d,%lf,%d,%d", &r.frame, &t, &r.camera, &r.delta) == 4)
      v.push_back(r);
  }
  return v;
}

void truncate_file(const fs::path& f, double keep) {
  const auto n = fs::file_size(f);
  fs::resize_file(f, static_cast<std::uintmax_t>(static_cast<double>(n) * keep));
}

TEST(KeepGoing, AVideoThatCannotBeOpenedBlindsItsCameraTheOthersRunOn) {
  const auto dir = testing::fresh_dir("kg_open");
  auto spec = testing::simple_dataset_spec(3, 12, true);
  spec.video_ext = ".mp4";
  spec.video_fourcc = "mp4v";
  testing::write_synth_dataset(dir / "ds", spec);
  const fs::path video = dir / "ds" / "cam_2.mp4";
  truncate_file(video, 0.5);  // the index (moov) is at the end: the file cannot be opened
  const std::string d = (dir / "ds").string();

  for (const std::string cmd : {"run", "detect"}) {
    const std::string extra = cmd == "run" ? " --no-overlays --no-plots" : " --quiet";
    auto r = test::run_netvmo(cmd + " " + d + " --out " + (dir / cmd).string() + extra, dir, 60);
    EXPECT_EQ(r.code, 1) << cmd;
    EXPECT_EQ(count_lines(r.err), 1) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find(video.string()), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / cmd)) << "nothing written";

    r = test::run_netvmo(cmd + " " + d + " --out " + (dir / cmd).string() + extra + " --keep-going",
                         dir, 60);
    EXPECT_EQ(r.code, 0) << cmd << ": " << r.err;
    EXPECT_EQ(count_lines_with(r.err, "warning"), 1) << cmd << ": one warning: " << r.err;
    EXPECT_NE(r.err.find(video.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("camera 2 is blind for the whole run"), std::string::npos) << r.err;
  }
  const auto rows = read_estimates(dir / "run" / "estimates.csv");
  ASSERT_EQ(rows.size(), 36u);
  for (const auto& row : rows) EXPECT_EQ(row.delta, row.camera == 2 ? 0 : 1) << row.frame;

  // A camera's own process: the same rule.
  const auto one = dir / "one";
  auto spec1 = testing::simple_dataset_spec(1, 6, true);
  spec1.video_ext = ".mp4";
  spec1.video_fourcc = "mp4v";
  testing::write_synth_dataset(one, spec1);
  truncate_file(one / "cam_1.mp4", 0.5);
  const std::string node = "node " + one.string() + " --camera 1 --domain " +
                           std::to_string(dds_domain()) + " --timeout 5 --frames 6 --out ";
  auto r = test::run_netvmo(node + (dir / "n1").string(), dir, 60);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find((one / "cam_1.mp4").string()), std::string::npos) << r.err;
  r = test::run_netvmo(node + (dir / "n2").string() + " --keep-going", dir, 60);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("camera 1 done: 6 frames"), std::string::npos) << r.out;
  std::ifstream csv(dir / "n2" / "node_1.csv");
  std::string line;
  std::getline(csv, line);
  int frames = 0;
  while (std::getline(csv, line)) {
    int k = -1, detected = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%*[^,],%d", &k, &detected), 2) << line;
    EXPECT_EQ(detected, 0) << line;
    ++frames;
  }
  EXPECT_EQ(frames, 6);
}

TEST(KeepGoing, AVideoThatStopsMidRunBlindsItsCameraFromThereOn) {
  const auto dir = testing::fresh_dir("kg_stop");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(3, 12, true));  // MJPG
  const fs::path video = dir / "ds" / "cam_3.avi";
  truncate_file(video, 0.5);  // the header still says 12 frames; decoding stops half way
  const std::string d = (dir / "ds").string();
  auto r = test::run_netvmo(
      "run " + d + " --out " + (dir / "a").string() + " --no-overlays --no-plots", dir, 60);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(video.string() + ": cannot decode frame"), std::string::npos) << r.err;

  r = test::run_netvmo(
      "run " + d + " --out " + (dir / "b").string() + " --no-overlays --no-plots --keep-going", dir,
      60);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(count_lines_with(r.err, "warning"), 1) << "one warning: " << r.err;
  EXPECT_NE(r.err.find("blind from that frame on"), std::string::npos) << r.err;
  int first_blind = -1, seen3 = 0;
  for (const auto& row : read_estimates(dir / "b" / "estimates.csv")) {
    if (row.camera != 3) {
      EXPECT_EQ(row.delta, 1) << row.camera << " " << row.frame;
      continue;
    }
    seen3 += row.delta;
    if (!row.delta && first_blind < 0) first_blind = row.frame;
    if (first_blind >= 0) {
      EXPECT_EQ(row.delta, 0) << "frame " << row.frame;
    }
  }
  EXPECT_GT(first_blind, 0) << "camera 3 saw its first frames";
  EXPECT_EQ(seen3, first_blind);
}

// ---------------------------------------------------------------------------------------------
// A node's journal lives in its unfinished folder, which --resume takes over.

TEST(OutputSafety, ResumeTakesOverOnlyAKilledRunsUnfinishedFolder) {
  const auto dir = testing::fresh_dir("takeover");
  const fs::path out = dir / "out";
  // A killed run's unfinished folder, and an older result left under a temporary name by a run
  // killed between its swap and the removal (it holds the marker).
  fs::create_directories(dir / "out.partial-999999991");
  std::ofstream(dir / "out.partial-999999991" / "rows.partial") << "kept\n";
  fs::create_directories(dir / "out.partial-999999992");
  std::ofstream(dir / "out.partial-999999992" / io::kOutputMarker) << "node\n";
  {
    io::OutputDir d(out, "node", /*resume=*/true);
    EXPECT_EQ(test::slurp(d.path() / "rows.partial"), "kept\n");
    EXPECT_FALSE(fs::exists(d.path() / io::kOutputMarker));
    d.commit();
  }
  EXPECT_EQ(siblings(out), (std::vector<std::string>{"out", "out.lock"}));
  EXPECT_EQ(test::slurp(out / "rows.partial"), "kept\n");
  // Without resume the same kind of unfinished folder is removed.
  fs::create_directories(dir / "out.partial-999999993");
  std::ofstream(dir / "out.partial-999999993" / "rows.partial") << "dropped\n";
  {
    io::OutputDir d(out, "node");
    EXPECT_FALSE(fs::exists(d.path() / "rows.partial"));
  }
  EXPECT_EQ(siblings(out), (std::vector<std::string>{"out", "out.lock"}));
}

// The complete rows of a node's journal (the header and a line cut off by a kill dropped).
std::vector<std::string> journal_rows(const fs::path& f) {
  std::vector<std::string> rows;
  const std::string s = test::slurp(f);
  size_t begin = s.find('\n');
  while (begin != std::string::npos) {
    const size_t end = s.find('\n', begin + 1);
    if (end == std::string::npos) break;
    rows.push_back(s.substr(begin + 1, end - begin - 1));
    begin = end;
  }
  return rows;
}

TEST(OutputSafety, AStandaloneNodeRestartedWithResumeKeepsItsPredecessorsRows) {
  const auto dir = testing::fresh_dir("resume");
  testing::write_synth_dataset(dir / "one", testing::simple_dataset_spec(1, 30));
  const fs::path out = dir / "node";
  // The common start is set only once the node is ready (the handshake `netvmo launch` uses), so
  // however late a loaded machine lets the node start, it begins at frame 0; the restarted node
  // reads the same start and joins late.
  fs::create_directories(dir / "handshake");
  const fs::path start_file = dir / "handshake" / "start.txt";
  // 30 frames at 30 frames/s at a quarter of real time: 4 s from the common start.
  const std::vector<std::string> argv = {kNetvmo,
                                         "node",
                                         (dir / "one").string(),
                                         "--camera",
                                         "1",
                                         "--domain",
                                         std::to_string(dds_domain()),
                                         "--mode",
                                         "async",
                                         "--speed",
                                         "0.25",
                                         "--start-file",
                                         start_file.string(),
                                         "--out",
                                         out.string(),
                                         "--timeout",
                                         "60"};
  const pid_t first = start(argv, dir / "first.log");
  const auto ready_by = Clock::now() + std::chrono::seconds(60);
  while (!fs::exists(dir / "handshake" / "node_1.ready") && Clock::now() < ready_by)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (!fs::exists(dir / "handshake" / "node_1.ready")) {
    ::kill(first, SIGKILL);
    ::waitpid(first, nullptr, 0);
    FAIL() << "the node was not ready within 60 s: " << test::slurp(dir / "first.log");
  }
  {
    const double start_epoch =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() +
        0.5;
    char text[40];
    std::snprintf(text, sizeof text, "%.6f\n", start_epoch);
    std::ofstream(dir / "handshake" / "start.txt.tmp") << text;
    fs::rename(dir / "handshake" / "start.txt.tmp", start_file);
  }
  const fs::path journal = dir / ("node.partial-" + std::to_string(first)) / "node_1.csv.partial";
  const auto until = Clock::now() + std::chrono::seconds(30);
  while (journal_rows(journal).size() < 5 && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(first, SIGKILL);
  int status = 0;
  ::waitpid(first, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status))
      << "finished before the kill: " << test::slurp(dir / "first.log");
  const auto before = journal_rows(journal);
  ASSERT_GE(before.size(), 5u) << test::slurp(dir / "first.log");
  ASSERT_LT(before.size(), 25u) << "killed too late to leave frames to the restarted node";
  EXPECT_FALSE(fs::exists(out)) << "no folder under the result's name before the node ends";

  auto resumed = argv;
  resumed.push_back("--resume");
  status = wait_bounded(start(resumed, dir / "second.log"), 60);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::slurp(dir / "second.log");
  EXPECT_EQ(siblings(out), (std::vector<std::string>{"node", "node.lock"}));
  std::ifstream csv(out / "node_1.csv");
  std::string line;
  std::getline(csv, line);  // header
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_GT(rows.size(), before.size());
  // The predecessor's finished rows, unchanged, then the restarted node's from its join on.
  for (size_t k = 0; k < before.size(); ++k) EXPECT_EQ(rows[k], before[k]) << "row " << k;
  EXPECT_EQ(rows.front().rfind("0,", 0), 0u) << rows.front();
  EXPECT_EQ(rows.back().rfind("29,", 0), 0u) << rows.back();
}

// ---------------------------------------------------------------------------------------------
// Crash safety: SIGKILL at seeded random points spread over a command's whole duration.

struct KillCampaign {
  std::string name;
  fs::path out;
  std::vector<std::string> argv;  // without --out
  int kills = 0;
  // Files whose content may differ between two complete runs (timings, encoders).
  std::vector<std::string> volatile_files;
};

bool is_volatile(const std::string& rel, const KillCampaign& c) {
  for (const auto& v : c.volatile_files)
    if (rel.size() >= v.size() && rel.compare(rel.size() - v.size(), v.size(), v) == 0) return true;
  return false;
}

void run_campaign(const KillCampaign& c, std::mt19937& rng, const fs::path& logs) {
  auto argv_of = [&](int) {
    auto a = c.argv;
    a.push_back("--out");
    a.push_back(c.out.string());
    return a;
  };
  // The previous result: one complete run, watched for when its temporary folder exists.
  const auto t0 = Clock::now();
  pid_t pid = start(argv_of(1), logs / (c.name + "_base.log"));
  const fs::path partial = c.out.string() + ".partial-" + std::to_string(pid);
  double seen_from = -1.0, seen_to = -1.0;
  int status = 0;
  for (const auto end = t0 + std::chrono::seconds(120);;) {
    const double t = std::chrono::duration<double>(Clock::now() - t0).count();
    if (::waitpid(pid, &status, WNOHANG) == pid) break;
    if (Clock::now() > end) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    if (fs::exists(partial)) {
      if (seen_from < 0) seen_from = t;
      seen_to = t;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const double duration = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
      << test::slurp(logs / (c.name + "_base.log"));
  auto before = snapshot(c.out);
  // Every other kill at a random time anywhere in the run (and a little after it); the others at
  // a random time within the base run's writing span after this run's temporary folder appears,
  // so that kills land while the command writes however long its start-up takes on a loaded
  // machine (a node's varies from 0.3 to 1.2 s, with 0.1 s of writing).
  std::uniform_real_distribution<double> anywhere(0.0, 1.1 * duration);
  std::uniform_real_distribution<double> writing(0.0, std::max(1e-3, seen_to - seen_from));
  int mid_run = 0, finished = 0, replaced = 0;
  std::set<std::string> stale;  // temporary folders killed runs may have left (until the next)
  for (int k = 0; k < c.kills; ++k) {
    const bool while_writing = k % 2 == 1;
    const double at = while_writing ? writing(rng) : anywhere(rng);
    const auto log = logs / (c.name + "_" + std::to_string(k) + ".log");
    pid = start(argv_of(k), log);
    bool reaped = false;
    if (while_writing) {
      const fs::path mine = c.out.string() + ".partial-" + std::to_string(pid);
      const auto until = Clock::now() + std::chrono::seconds(60);
      while (!fs::exists(mine) && Clock::now() < until &&
             !(reaped = ::waitpid(pid, &status, WNOHANG) == pid))
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    if (!reaped) {
      std::this_thread::sleep_for(std::chrono::duration<double>(at));
      ::kill(pid, SIGKILL);  // harmless if it has already exited (not yet reaped)
      ::waitpid(pid, &status, 0);
    }
    const bool killed = WIFSIGNALED(status);
    if (killed) stale.insert(c.out.filename().string() + ".partial-" + std::to_string(pid));
    if (!killed) {
      ++finished;
      EXPECT_EQ(WEXITSTATUS(status), 0) << test::slurp(log);
    }
    // Under the result's name: the previous result, intact, or (killed after the swap, or
    // finished) a complete new one with the same files and the same deterministic content.
    ASSERT_TRUE(fs::is_directory(c.out)) << c.name << " kill " << k << " at " << at << " s";
    const auto after = snapshot(c.out);
    if (after != before) {
      std::vector<std::string> a, b;
      for (const auto& [rel, content] : after) a.push_back(rel);
      for (const auto& [rel, content] : before) b.push_back(rel);
      ASSERT_EQ(a, b) << c.name << " kill " << k << " at " << at << " s: files differ";
      for (const auto& [rel, content] : after) {
        if (is_volatile(rel, c))
          EXPECT_FALSE(content.empty()) << rel;
        else
          EXPECT_EQ(content, before.at(rel)) << c.name << " kill " << k << ": " << rel;
      }
      if (after.count("summary.json")) {
        EXPECT_TRUE(nlohmann::json::accept(after.at("summary.json")));
      }
      before = after;
      ++replaced;
    }
    // Nothing else under the result's name but the lock and a stale temporary folder.
    for (const auto& s : siblings(c.out)) {
      const std::string base = c.out.filename().string();
      const bool ok = s == base || s == base + ".lock" || stale.count(s);
      EXPECT_TRUE(ok) << c.name << " kill " << k << ": left " << s;
      if (killed && s == base + ".partial-" + std::to_string(pid)) ++mid_run;
    }
  }
  std::printf(
      "%s: %d kills over %.2f s runs (temporary folder seen %.2f-%.2f s): %d left a temporary "
      "folder, %d found a new result in place, %d had finished\n",
      c.name.c_str(), c.kills, duration, seen_from, seen_to, mid_run, replaced, finished);
  EXPECT_GT(mid_run, 0) << "no kill landed while the command was writing";
  // The next run cleans what killed runs left.
  pid = start(argv_of(0), logs / (c.name + "_last.log"));
  status = wait_bounded(pid, 120);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  const std::string base = c.out.filename().string();
  EXPECT_EQ(siblings(c.out), (std::vector<std::string>{base, base + ".lock"}));
}

TEST(CrashSafety, SigkillAtRandomPointsLeavesThePreviousResultIntact) {
  const auto dir = testing::fresh_dir("crash");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(3, 20));
  testing::write_synth_dataset(dir / "one", testing::simple_dataset_spec(1, 10));
  fs::create_directories(dir / "logs");
  std::mt19937 rng(20261123);
  const std::vector<KillCampaign> campaigns = {
      {"run_overlays",
       dir / "run_overlays",
       {kNetvmo, "run", (dir / "ds").string()},
       10,
       {"summary.json", ".png", ".mp4"}},
      {"render",
       dir / "render_out",
       {kNetvmo, "render", kScenario, "--frames", "3", "--spp", "1", "--quiet"},
       8,
       {}},
      {"node",
       dir / "node_out",
       {kNetvmo, "node", (dir / "one").string(), "--camera", "1", "--domain",
        std::to_string(dds_domain()), "--timeout", "5"},
       6,
       {"node_1.json"}},
  };
  int total = 0;
  for (const auto& c : campaigns) {
    if (c.kills == 0) continue;
    run_campaign(c, rng, dir / "logs");
    total += c.kills;
  }
  EXPECT_GE(total, 20);
}

}  // namespace
}  // namespace netvmo
