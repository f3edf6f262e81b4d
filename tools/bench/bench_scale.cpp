// Lock-step exchange rounds of n camera processes on one machine over Cyclone DDS (the loopback
// configuration): every process is one camera of a 3-regular graph (its ring neighbours i - 1,
// i + 1 and the opposite camera i + n/2; n = 2: one edge), with a DdsTransport on its own estimate
// topic and a CameraObserver without a front end (a fixed, blind camera: 64 front ends would not
// fit on 2 cores, and the exchange is what scales), running kRounds lock-step rounds. Per n it
// prints: discovery_s (from the fork to the slowest node matched with all its neighbours'
// writers), received_per_round (estimates a node takes per round: its degree when only the
// neighbours' topics are read, n - 1 with one topic for all), round_median_us (the median over
// nodes of each node's median round) and round_p99_us. The anchor, in the same run: n = 2.
#include <benchmark/benchmark.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/exchange.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

using namespace netvmo;
namespace fs = std::filesystem;

namespace {

constexpr int kRounds = 300;

std::vector<int> neighbours(int i, int n) {
  if (n == 2) return {1 - i};
  std::vector<int> v = {(i + 1) % n, (i + n - 1) % n, (i + n / 2) % n};
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// One camera's process: writes "<matched epoch> <median us> <p99 us> <received>" to `out`.
int camera(int i, int n, int domain, const fs::path& out) {
  std::vector<int> labels;
  for (int k = 0; k < n; ++k) labels.push_back(k + 1);
  const auto nb = neighbours(i, n);
  net::DdsSettings ds;
  ds.domain = domain;
  ds.timeout_s = 120.0;
  net::DdsTransport t(i, nb, labels, ds);
  if (!t.wait_for_writers(static_cast<int>(nb.size()), 120.0)) return 2;
  const double matched = epoch_seconds();
  obs::CameraObserver cam(i, nb, obs::ObserverSettings{});
  std::vector<obs::EstimateMessage> inbox;
  std::vector<double> us;
  for (int k = 0; k < kRounds; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    obs::send_estimate(cam, t);  // one exchange round (exchange.hpp)
    obs::take_estimates(cam, t, inbox);
    cam.step(1e-3);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  t.flush(10.0);
  std::sort(us.begin(), us.end());
  std::ofstream f(out);
  f.precision(17);
  f << matched << " " << us[us.size() / 2] << " " << us[us.size() * 99 / 100] << " "
    << t.stats().received << "\n";
  return f ? 0 : 3;
}

void BM_LockStepRoundNProcesses(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const fs::path dir =
      fs::temp_directory_path() /
      ("netvmo_bench_scale_" + std::to_string(::getpid()) + "_" + std::to_string(n));
  fs::create_directories(dir);
  net::write_loopback_config(dir / "cyclonedds.xml");
  net::use_config(dir / "cyclonedds.xml");
  const int domain = 1 + (net::domain_from_pid(::getpid()) + n) % 200;
  for (auto _ : state) {
    const double t_fork = epoch_seconds();
    std::vector<pid_t> pids;
    for (int i = 0; i < n; ++i) {
      const pid_t p = ::fork();
      if (p == 0) {
        int rc = 1;
        try {
          rc = camera(i, n, domain, dir / ("camera_" + std::to_string(i) + ".txt"));
        } catch (...) {
        }
        ::_exit(rc);
      }
      pids.push_back(p);
    }
    const auto res = net::supervise(pids, 600.0, true);
    double matched = 0.0;
    std::vector<double> medians, p99s;
    double received = 0.0;
    int ok = 0;
    for (int i = 0; i < n; ++i) {
      std::ifstream f(dir / ("camera_" + std::to_string(i) + ".txt"));
      double m = 0, med = 0, p99 = 0, rec = 0;
      if (!(f >> m >> med >> p99 >> rec)) continue;
      ++ok;
      matched = std::max(matched, m);
      medians.push_back(med);
      p99s.push_back(p99);
      received += rec;
    }
    if (ok != n) {
      state.SkipWithError((std::to_string(n - ok) + " camera processes failed").c_str());
      break;
    }
    std::sort(medians.begin(), medians.end());
    std::sort(p99s.begin(), p99s.end());
    state.counters["discovery_s"] = matched - t_fork;
    state.counters["received_per_round"] = received / n / kRounds;
    state.counters["round_median_us"] = medians[medians.size() / 2];
    state.counters["round_p99_us"] = p99s[p99s.size() / 2];
    (void)res;
  }
  fs::remove_all(dir);
}
BENCHMARK(BM_LockStepRoundNProcesses)
    ->ArgName("n")
    ->Arg(2)
    ->Arg(16)
    ->Arg(32)
    ->Arg(64)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
