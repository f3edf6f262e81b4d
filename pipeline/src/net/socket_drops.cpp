#include "netvmo/pipeline/net/socket_drops.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

namespace netvmo::net {
namespace fs = std::filesystem;

std::uint64_t udp_drops_in(std::istream& table, const std::set<unsigned long>& inodes) {
  // sl local_address rem_address st tx_queue:rx_queue tr:tm->when retrnsmt uid timeout inode
  // ref pointer drops (linux/net/ipv4/udp.c, udp4_format_sock)
  std::uint64_t drops = 0;
  std::string line;
  while (std::getline(table, line)) {
    std::istringstream row(line);
    std::string sl, local, remote, st, queues, timer, retr;
    unsigned long uid = 0, timeout = 0, inode = 0, ref = 0;
    std::string pointer;
    std::uint64_t d = 0;
    if (!(row >> sl >> local >> remote >> st >> queues >> timer >> retr >> uid >> timeout >>
          inode >> ref >> pointer >> d))
      continue;
    if (inodes.count(inode)) drops += d;
  }
  return drops;
}

std::set<unsigned long> own_socket_inodes() {
  std::set<unsigned long> inodes;
  std::error_code ec;
  for (fs::directory_iterator it("/proc/self/fd", ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code lc;
    const std::string target = fs::read_symlink(it->path(), lc).string();
    if (lc || target.rfind("socket:[", 0) != 0) continue;  // closed meanwhile, or not a socket
    try {
      inodes.insert(std::stoul(target.substr(8)));
    } catch (const std::exception&) {
    }
  }
  return inodes;
}

std::optional<std::uint64_t> udp_drops_of_this_process() {
  const auto inodes = own_socket_inodes();
  std::optional<std::uint64_t> total;
  for (const char* file : {"/proc/net/udp", "/proc/net/udp6"}) {
    std::ifstream table(file);
    if (!table) continue;
    total = total.value_or(0) + udp_drops_in(table, inodes);
  }
  return total;
}

std::string kernel_drops_consequence(std::uint64_t n) {
  return "the kernel dropped " + std::to_string(n) +
         " datagram(s) addressed to this node, its socket receive buffer full: images of a "
         "best-effort topic may be lost (docs/ros2.md, \"Socket receive buffers\")";
}

}  // namespace netvmo::net
