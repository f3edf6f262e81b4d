// Fuzz target: an estimate received from another camera's process, from the raw bytes on the
// wire to the observer. The input is a serialized netvmo::msg::Estimate payload as Cyclone DDS
// receives it (4-byte encapsulation header, then XCDR1 or XCDR2 data); it goes through what
// Cyclone does with a received sample (dds_stream_normalize, then dds_stream_read_sample, the
// steps of its default serdata) and then what DdsTransport does (net::decode_estimate: graph
// digest check, conversion) and CameraObserver::receive's checks, and one observer step with
// whatever was accepted.
#include <cstring>
#include <string>
#include <vector>

#include "NetvmoEstimate.h"
#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"

using namespace netvmo;

namespace {

// Cyclone's receive path for one payload (ros::decode: dds_stream_normalize, then
// dds_stream_read_sample, the steps of its default serdata, in 8-byte aligned memory with 8
// bytes of slack): false when Cyclone would drop it as malformed. A write past the slack stops
// the fuzzer (corpus entry cyclone_xcdr2_bswap_overrun; docs/hardening.md, "Findings, fixed").
bool deserialize(const std::uint8_t* data, std::size_t size,
                 ros::Decoded<netvmo_msg_Estimate>& out) {
  if (size > (1u << 20)) return false;
  std::string why;
  if (out.read(data, size, why)) return true;
  if (why.rfind(ros::kWrotePastThePayload, 0) == 0) __builtin_trap();
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ros::Decoded<netvmo_msg_Estimate> s(netvmo_msg_Estimate_desc);  // (frees its echoes)
  if (!deserialize(data, size, s)) return 0;
  // Camera index 0 (id 1) of three, neighbours 1 and 2; a non-zero graph digest of its own.
  const std::vector<int> labels = {1, 2, 3};
  const std::uint64_t digest = net::graph_digest(labels, {{1, 2}, {1, 3}});
  obs::EstimateMessage m;
  try {
    m = net::decode_estimate(*s, digest, 0, labels);
  } catch (const net::GraphMismatch&) {
    return 0;
  }
  obs::CameraObserver cam(0, {1, 2}, obs::ObserverSettings{});
  (void)cam.receive(m);
  // The echoes, as the transport's clock takes them (every value, finite or not).
  net::ClockSync clock(0, {1, 2});
  std::vector<net::ClockEcho> echoes;
  for (std::uint32_t e = 0; e < s->echoes._length; ++e)
    echoes.push_back(
        {s->echoes._buffer[e].camera, s->echoes._buffer[e].sent, s->echoes._buffer[e].received});
  clock.taken(s->sender, s->sent, 0.0, echoes.data(), echoes.size());
  (void)clock.to_own_clock(s->sender, s->stamp);
  cam.step(1.0 / 330.0);
  return 0;
}
