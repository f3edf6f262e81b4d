// Cyclone DDS configuration for cameras as processes. The configuration netvmo writes keeps all
// traffic on this machine: the loopback interface only, multicast off, unicast discovery with
// the single peer 127.0.0.1. Every process netvmo starts gets it through CYCLONEDDS_URI.
// Deployments over several machines adapt datasets/cyclonedds_multihost.template.xml instead
// (docs/processes.md, "Several machines"); netvmo never uses that template by itself.
#pragma once

#include <filesystem>
#include <string>

namespace netvmo::net {

/// Largest participant index the loopback configuration probes during unicast discovery: at
/// most this many + 1 participants (nodes, tools) per domain on the machine.
constexpr int kMaxParticipants = 100;

/// The loopback-only configuration (XML) for any domain id.
std::string loopback_config_xml();

/// Writes loopback_config_xml() to `file` (atomically); throws InputError naming it on failure.
void write_loopback_config(const std::filesystem::path& file);

/// A domain id in [1, 200] derived from a process id, so that parallel runs on one machine do
/// not meet (Cyclone's ports 7400 + 250 d + ... stay below 65536 for such d).
int domain_from_pid(long pid);

/// Sets CYCLONEDDS_URI for this process (and those it starts) to `file`.
void use_config(const std::filesystem::path& file);

}  // namespace netvmo::net
