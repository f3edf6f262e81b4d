// DDS Security for the camera processes (docs/processes.md, "Security"): Cyclone DDS's
// authentication, access-control and cryptography plugins (Debian's libddsc0debian), configured
// per participant through its QoS properties, and a test PKI written with OpenSSL.
//
// A security folder holds
//   identity_ca.pem, permissions_ca.pem   the two certificate authorities (EC prime256v1)
//   governance.p7s                        the domain's rules, S/MIME-signed by the permissions CA:
//                                         no unauthenticated participant, discovery, liveliness
//                                         and every topic's data encrypted, read and write access
//                                         controlled
//   <name>.cert.pem, <name>.key.pem       each identity's certificate (subject CN=<name>,
//                                         O=netvmo, signed by the identity CA) and private key
//   <name>.permissions.p7s                what <name> may do, signed by the permissions CA
// Identities: cam_<id> per camera of network.yaml (publish its own estimate topic and its ROS 2
// outputs, subscribe its neighbours' estimate topics and its own camera topics), `viewer` (a ROS 2
// tool: subscribe every camera's ROS 2 outputs) and `player` (publish the camera topics: play).
#pragma once

#include <dds/dds.h>

#include <filesystem>
#include <string>

#include "netvmo/pipeline/io/network_config.hpp"

namespace netvmo::net {

/// One participant's security files.
struct SecurityIdentity {
  std::string name;  ///< cam_<id>, viewer or player
  std::filesystem::path identity_ca, permissions_ca, governance, certificate, private_key,
      permissions;
};

/// The identity of camera `camera_id`: "cam_<id>".
std::string camera_identity(int camera_id);

/// Identity `name`'s files in the security folder `dir`. Throws InputError naming the first
/// missing file.
SecurityIdentity security_identity(const std::filesystem::path& dir, const std::string& name);

/// Writes a test PKI for the cameras and graph of `net` into `dir` (created; files replaced),
/// valid from now for `days` days. Throws InputError when a file cannot be written,
/// std::runtime_error when OpenSSL fails. A real deployment keeps the CAs' keys off the cameras
/// (docs/processes.md, "Security").
void write_test_pki(const std::filesystem::path& dir, const io::NetworkConfig& net, int days = 365);

/// A participant QoS that loads the three plugins with `id`'s files (the caller deletes it).
dds_qos_t* security_qos(const SecurityIdentity& id);

/// A participant on `domain`, secured with `id` when given (CYCLONEDDS_URI's configuration).
/// Throws std::runtime_error naming `what` when Cyclone DDS refuses (with security: a bad
/// certificate, permissions that do not grant the domain, ...).
dds_entity_t create_participant(int domain, const SecurityIdentity* id, const char* what);

}  // namespace netvmo::net
