// Lock-step exchange rounds between two processes over Cyclone DDS on the loopback interface:
// each round both publish their estimate and wait for the other's (DdsTransport). The other
// process is forked before this one creates any DDS entity. Loopback-only configuration,
// domain derived from the pid. Both send as soon as they hold the other's previous estimate, so
// one round is one message's trip (publish -> take in the other process) plus a step: the
// median and p99 of the round times are the one-way latency (a ping-pong round trip / 2).
#include <benchmark/benchmark.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"

using namespace netvmo;

namespace {

constexpr int kRounds = 3000;

void run_rounds(int self, int domain, int rounds, benchmark::State* state,
                std::vector<double>* round_us = nullptr) {
  net::DdsSettings ds;
  ds.domain = domain;
  ds.timeout_s = 10.0;
  net::DdsTransport t(self, {1 - self}, {1, 2}, ds);
  t.wait_for_writers(2, 10.0);
  obs::CameraObserver cam(self, {1 - self}, obs::ObserverSettings{});
  std::vector<obs::EstimateMessage> inbox;
  auto round = [&] {
    t.send(cam.publish());
    t.receive(self, inbox);
    for (const auto& m : inbox) cam.receive(m);
    cam.step(1e-3);
  };
  if (state) {
    for (auto _ : *state) {
      const auto t0 = std::chrono::steady_clock::now();
      round();
      if (round_us)
        round_us->push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                .count());
    }
  } else {
    for (int k = 0; k < rounds; ++k) round();
  }
  t.flush(5.0);
}

void BM_LockStepRoundTwoProcesses(benchmark::State& state) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("netvmo_bench_dds_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  net::write_loopback_config(dir / "cyclonedds.xml");
  net::use_config(dir / "cyclonedds.xml");
  const int domain = net::domain_from_pid(::getpid());
  const pid_t peer = ::fork();
  if (peer == 0) {
    try {
      run_rounds(1, domain, kRounds, nullptr);
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  std::vector<double> us;
  us.reserve(kRounds);
  run_rounds(0, domain, kRounds, &state, &us);
  int status = 0;
  ::waitpid(peer, &status, 0);
  std::filesystem::remove_all(dir);
  state.counters["rounds_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  std::sort(us.begin(), us.end());
  if (!us.empty()) {
    state.counters["median_us"] = us[us.size() / 2];
    state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  }
}
BENCHMARK(BM_LockStepRoundTwoProcesses)
    ->Iterations(kRounds)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
