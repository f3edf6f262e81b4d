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
#include <sstream>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"
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

/// `netvmo ARGS` from the build folder, killed after `seconds` (and 5 s later for good).
inline test::CliResult netvmo_bounded(const std::string& args, const std::filesystem::path& scratch,
                                      int seconds) {
  return test::run_netvmo(args, scratch, seconds);
}

/// A CSV file's rows (header included), cells as text (a trailing empty cell kept).
inline std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& f) {
  std::ifstream in(f);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> row;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) row.push_back(cell);
    if (!line.empty() && line.back() == ',') row.emplace_back();
    rows.push_back(row);
  }
  return rows;
}

/// A pose written by a node (position, then the rotation row-major) from cell `first` on.
inline obs::SE3 pose_at(const std::vector<std::string>& row, size_t first) {
  obs::SE3 g = obs::SE3::Identity();
  for (int r = 0; r < 3; ++r) g.translation()(r) = std::stod(row[first + r]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g.linear()(r, c) = std::stod(row[first + 3 + 3 * r + c]);
  return g;
}

inline nlohmann::json read_json(const std::filesystem::path& f) {
  std::ifstream in(f);
  return nlohmann::json::parse(in);
}

}  // namespace netvmo::net_test
