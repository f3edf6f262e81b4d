// Datagrams the kernel dropped before this process read them: a UDP socket whose receive buffer
// is full drops what arrives (Linux counts them per socket, the `drops` column of /proc/net/udp).
// For a best-effort stream (a live camera's images) nothing resends them, so a node reports the
// count next to what it received (docs/ros2.md, "Socket receive buffers").
#pragma once

#include <cstdint>
#include <istream>
#include <optional>
#include <set>
#include <string>

namespace netvmo::net {

/// The sum of the `drops` column of a /proc/net/udp or /proc/net/udp6 table over the rows whose
/// `inode` is in `inodes`; rows that do not parse are skipped (the header among them).
std::uint64_t udp_drops_in(std::istream& table, const std::set<unsigned long>& inodes);

/// The inodes of the sockets this process holds open (/proc/self/fd's "socket:[inode]" links).
std::set<unsigned long> own_socket_inodes();

/// Datagrams dropped on this process's open UDP sockets (IPv4 and IPv6) since they were
/// opened; nullopt where /proc/net/udp cannot be read (not Linux). Sockets already closed are
/// not counted: sample it while the participant that owns them lives.
std::optional<std::uint64_t> udp_drops_of_this_process();

/// What `n` (> 0) drops mean, for a node's warning and for its error when no image came: "the
/// kernel dropped n datagram(s) addressed to this node, its socket receive buffer full: ...".
std::string kernel_drops_consequence(std::uint64_t n);

}  // namespace netvmo::net
