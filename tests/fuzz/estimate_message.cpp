// Fuzz target: an estimate received from another camera's process, from the raw bytes on the
// wire to the observer. The input is a serialized netvmo::msg::Estimate payload as Cyclone DDS
// receives it (4-byte encapsulation header, then XCDR1 or XCDR2 data); it goes through what
// Cyclone does with a received sample (dds_stream_normalize, then dds_stream_read_sample, the
// steps of its default serdata) and then what DdsTransport does (net::decode_estimate: graph
// digest check, conversion) and CameraObserver::receive's checks, and one observer step with
// whatever was accepted.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata_default.h>

#include <cstring>
#include <vector>

#include "NetvmoEstimate.h"
#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"

using namespace netvmo;

namespace {

// The sertype Cyclone builds for the generated descriptor, reduced to what the CDR stream
// functions read (the descriptor's size, alignment, flags and ops; no key).
ddsi_sertype_default make_sertype() {
  ddsi_sertype_default st;
  std::memset(&st, 0, sizeof st);
  const dds_topic_descriptor_t& d = netvmo_msg_Estimate_desc;
  st.encoding_format = 0;  // CDR_ENC_FORMAT_PLAIN: a @final struct
  st.type.size = d.m_size;
  st.type.align = d.m_align;
  st.type.flagset = d.m_flagset;
  st.type.ops.nops = dds_stream_countops(d.m_ops, d.m_nkeys, d.m_keys);
  st.type.ops.ops = const_cast<uint32_t*>(d.m_ops);
  return st;
}

// Cyclone's receive path for one payload: false when Cyclone would drop it as malformed.
bool deserialize(const std::uint8_t* data, std::size_t size, netvmo_msg_Estimate& out) {
  static const ddsi_sertype_default st = make_sertype();
  if (size < 4 || size > (1u << 20)) return false;
  const unsigned id = (unsigned(data[0]) << 8) | data[1];
  // CDR_BE 0, CDR_LE 1 (XCDR1); CDR2_BE 6, CDR2_LE 7 (XCDR2, plain): a final type's encodings.
  if (id != 0 && id != 1 && id != 6 && id != 7) return false;
  const bool little = (id & 1u) != 0;
  const uint32_t xcdr = id >= 6 ? 2 : 1;
  const bool bswap = little != (DDSRT_ENDIAN == DDSRT_LITTLE_ENDIAN);
  // The payload after the header, in 8-byte aligned memory as Cyclone's serdata keeps it, with
  // 8 bytes of slack and a guard after it. Cyclone 0.10.2's normalize byte-swaps the 8-byte
  // field that straddles the end of a truncated big-endian XCDR2 payload before rejecting it
  // (corpus entry cyclone_xcdr2_bswap_overrun; docs/hardening.md, "Findings, fixed"): the slack
  // absorbs that, and a write past the slack stops the fuzzer.
  const uint32_t n = static_cast<uint32_t>(size - 4);
  constexpr std::size_t kSlack = 8, kGuard = 64;
  constexpr unsigned char kPattern = 0x5a;
  std::vector<std::uint64_t> buf((n + kSlack + kGuard + 7) / 8);
  auto* bytes = reinterpret_cast<unsigned char*>(buf.data());
  std::memset(bytes, kPattern, buf.size() * 8);
  std::memcpy(bytes, data + 4, n);
  uint32_t actual = 0;
  const bool valid = dds_stream_normalize(buf.data(), n, bswap, xcdr, &st, false, &actual);
  for (std::size_t k = n + kSlack; k < buf.size() * 8; ++k)
    if (bytes[k] != kPattern) __builtin_trap();  // normalize wrote past the payload's slack
  if (!valid) return false;
  dds_istream_t is;
  dds_istream_init(&is, actual, buf.data(), xcdr);
  std::memset(&out, 0, sizeof out);
  dds_stream_read_sample(&is, &out, &st);
  dds_istream_fini(&is);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  netvmo_msg_Estimate s;
  if (!deserialize(data, size, s)) return 0;
  // Camera index 0 (id 1) of three, neighbours 1 and 2; a non-zero graph digest of its own.
  const std::vector<int> labels = {1, 2, 3};
  const std::uint64_t digest = net::graph_digest(labels, {{1, 2}, {1, 3}});
  obs::EstimateMessage m;
  try {
    m = net::decode_estimate(s, digest, 0, labels);
  } catch (const net::GraphMismatch&) {
    return 0;
  }
  obs::CameraObserver cam(0, {1, 2}, obs::ObserverSettings{});
  (void)cam.receive(m);
  cam.step(1.0 / 330.0);
  return 0;
}
