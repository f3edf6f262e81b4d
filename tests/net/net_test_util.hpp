// Helpers of the DDS tests: a loopback-only Cyclone configuration and a domain of this test
// process's own, and running child processes under a time limit.
#pragma once

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
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

/// A UDP socket of this process bound on 127.0.0.1 with a receive buffer of `receive_buffer`
/// bytes (the kernel doubles it and keeps a minimum), and a socket that sends to it; both closed
/// on destruction. Datagrams sent faster than they are read overflow the buffer, and the kernel
/// drops them (socket_drops.hpp).
class LoopbackUdpPair {
 public:
  explicit LoopbackUdpPair(int receive_buffer) {
    rx_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    tx_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    to_.sin_family = AF_INET;
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof to_;
    ok_ = rx_ >= 0 && tx_ >= 0 &&
          ::setsockopt(rx_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer) == 0 &&
          ::bind(rx_, reinterpret_cast<sockaddr*>(&to_), sizeof to_) == 0 &&
          ::getsockname(rx_, reinterpret_cast<sockaddr*>(&to_), &len) == 0;
  }
  ~LoopbackUdpPair() {
    close_receiver();
    if (tx_ >= 0) ::close(tx_);
  }
  LoopbackUdpPair(const LoopbackUdpPair&) = delete;
  LoopbackUdpPair& operator=(const LoopbackUdpPair&) = delete;

  /// Both sockets made, the receiver bound.
  bool ok() const { return ok_; }
  /// Sends `count` datagrams of `bytes` zero bytes (at most 65000) to the receiver; true if
  /// every one was sent whole.
  bool send(int count, size_t bytes) {
    const std::vector<char> payload(bytes, 0);
    for (int k = 0; k < count; ++k)
      if (::sendto(tx_, payload.data(), bytes, 0, reinterpret_cast<const sockaddr*>(&to_),
                   sizeof to_) != static_cast<ssize_t>(bytes))
        return false;
    return true;
  }
  /// Reads what is waiting without blocking; returns the number of datagrams read.
  int read_waiting() {
    char buffer[65536];
    int read = 0;
    while (rx_ >= 0 && ::recv(rx_, buffer, sizeof buffer, MSG_DONTWAIT) > 0) ++read;
    return read;
  }
  void close_receiver() {
    if (rx_ >= 0) ::close(rx_);
    rx_ = -1;
  }

 private:
  int rx_ = -1, tx_ = -1;
  sockaddr_in to_{};
  bool ok_ = false;
};

}  // namespace netvmo::net_test
