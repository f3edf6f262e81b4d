// What the kernel dropped on this process's UDP sockets (socket_drops.hpp): the table's columns,
// and a socket whose receive buffer is made to overflow on the loopback interface; the receive
// buffers netvmo's loopback configuration asks for (cyclone_config.cpp).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "net_test_util.hpp"
#include "netvmo/pipeline/net/socket_drops.hpp"

using namespace netvmo;

TEST(SocketDrops, TheDropsColumnIsSummedOverTheGivenSocketsOnly) {
  // /proc/net/udp's layout (header, then one row per socket; inode 10th, drops 13th).
  std::istringstream table(
      "   sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  "
      "timeout inode ref pointer drops\n"
      "  1: 0100007F:1D10 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        "
      "0 4242 2 0000000000000000 7\n"
      "  2: 0100007F:1D11 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        "
      "0 4343 2 0000000000000000 11\n"
      "  3: 0100007F:1D12 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        "
      "0 4444 2 0000000000000000 13\n"
      "a row cut short: 0100007F:1D13\n");
  EXPECT_EQ(net::udp_drops_in(table, {4242, 4444, 9999}), 7u + 13u);
  std::istringstream again(table.str());
  EXPECT_EQ(net::udp_drops_in(again, {}), 0u);
}

TEST(SocketDrops, AFullReceiveBufferIsCountedForThisProcess) {
  // The kernel's minimum is about 4 KiB (SOCK_MIN_RCVBUF, doubled).
  net_test::LoopbackUdpPair pair(4096);
  ASSERT_TRUE(pair.ok());
  const auto before = net::udp_drops_of_this_process();
  ASSERT_TRUE(before.has_value()) << "/proc/net/udp not readable";
  const int sent = 200;
  ASSERT_TRUE(pair.send(sent, 1000));
  // Every datagram is either read or counted as dropped, once the loopback has delivered them.
  int read = 0;
  std::uint64_t dropped = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < give_up) {
    read += pair.read_waiting();
    dropped = net::udp_drops_of_this_process().value_or(0) - *before;
    if (read + static_cast<int>(dropped) >= sent) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(read + static_cast<int>(dropped), sent) << read << " read, " << dropped << " dropped";
  EXPECT_GT(dropped, 0u) << "a 4 KiB buffer held 200 datagrams of 1000 bytes";
  EXPECT_GT(read, 0);
  // A closed socket's drops are no longer this process's.
  pair.close_receiver();
  EXPECT_EQ(net::udp_drops_of_this_process().value_or(0), *before);
}

namespace {

// The receive buffer of each UDP socket this process holds, by file descriptor.
std::map<int, int> udp_receive_buffers() {
  std::map<int, int> out;
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) {
    int fd = -1;
    try {
      fd = std::stoi(e.path().filename().string());
    } catch (const std::exception&) {
      continue;
    }
    int type = 0, size = 0;
    socklen_t len = sizeof type;
    if (::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_DGRAM) continue;
    len = sizeof size;
    if (::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, &len) == 0) out[fd] = size;
  }
  return out;
}

}  // namespace

TEST(SocketDrops, TheLoopbackConfigurationAsksForSixteenMebibytesAndTakesWhatTheKernelGives) {
  const auto dir = test::scratch_dir("sockbuf");
  const int domain = net_test::loopback_domain(dir);
  long rmem_max = 0;
  std::ifstream("/proc/sys/net/core/rmem_max") >> rmem_max;
  ASSERT_GT(rmem_max, 0) << "/proc/sys/net/core/rmem_max not readable";
  const auto before = udp_receive_buffers();
  const dds_entity_t p = dds_create_participant(domain, nullptr, nullptr);
  ASSERT_GT(p, 0) << dds_strretcode(p);
  int largest = 0, opened = 0;
  for (const auto& [fd, size] : udp_receive_buffers())
    if (!before.count(fd)) {
      ++opened;
      largest = std::max(largest, size);
    }
  dds_delete(p);
  ASSERT_GT(opened, 0) << "the participant opened no UDP socket";
  // The kernel caps a request at net.core.rmem_max and reports twice what it grants (its
  // bookkeeping overhead); Cyclone's default request, 1 MiB, would give 2 MiB where the cap is
  // higher.
  const long asked = 16L << 20;
  EXPECT_EQ(largest, 2 * std::min(asked, rmem_max)) << "net.core.rmem_max " << rmem_max;
}
