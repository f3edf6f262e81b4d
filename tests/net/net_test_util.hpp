// Helpers of the DDS tests: a loopback-only Cyclone configuration and a domain of this test
// process's own, and running child processes under a time limit.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "test_util.hpp"

namespace netvmo::net_test {

/// Writes the loopback configuration into `dir`, points CYCLONEDDS_URI at it and returns the
/// domain id of this test process (printed).
inline int loopback_domain(const std::filesystem::path& dir) {
  net::write_loopback_config(dir / "cyclonedds.xml");
  net::use_config(dir / "cyclonedds.xml");
  const int d = net::domain_from_pid(::getpid());
  std::printf("DDS domain %d (loopback only)\n", d);
  return d;
}

/// Runs the commands in parallel, each killed after `timeout_s`; returns their results.
inline std::vector<net::ChildResult> run_all(const std::vector<std::vector<std::string>>& cmds,
                                             const std::filesystem::path& dir, double timeout_s) {
  std::vector<pid_t> pids;
  for (size_t k = 0; k < cmds.size(); ++k)
    pids.push_back(net::spawn(cmds[k], dir / ("child_" + std::to_string(k) + ".log")));
  return net::supervise(pids, timeout_s, true);
}

/// `netvmo ARGS` from the build folder, killed after `seconds` (test::run_netvmo).
inline test::CliResult netvmo_bounded(const std::string& args, const std::filesystem::path& scratch,
                                      int seconds) {
  return test::run_netvmo(args, scratch, seconds);
}

inline nlohmann::json read_json(const std::filesystem::path& f) {
  std::ifstream in(f);
  return nlohmann::json::parse(in);
}

}  // namespace netvmo::net_test
