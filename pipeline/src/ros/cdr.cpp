#include "netvmo/pipeline/ros/cdr.hpp"

#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata_default.h>

#include <cstring>

namespace netvmo::ros {

namespace {

// The sertype Cyclone builds for a generated descriptor, reduced to what the CDR stream
// functions read (size, alignment, flags and ops; the types here have no key).
ddsi_sertype_default sertype(const dds_topic_descriptor_t& d) {
  ddsi_sertype_default st;
  std::memset(&st, 0, sizeof st);
  st.encoding_format = 0;  // CDR_ENC_FORMAT_PLAIN: a @final struct
  st.type.size = d.m_size;
  st.type.align = d.m_align;
  st.type.flagset = d.m_flagset;
  st.type.ops.nops = dds_stream_countops(d.m_ops, d.m_nkeys, d.m_keys);
  st.type.ops.ops = const_cast<uint32_t*>(d.m_ops);
  return st;
}

}  // namespace

bool decode(const dds_topic_descriptor_t& desc, const std::uint8_t* data, std::size_t size,
            void* sample, std::string& why_not) {
  std::memset(sample, 0, desc.m_size);
  if (size < 4) {
    why_not = "shorter than its 4-byte encapsulation header";
    return false;
  }
  if (size - 4 > 0xffffffffu - 64) {
    why_not = "larger than 4 GiB";
    return false;
  }
  const unsigned id = (unsigned(data[0]) << 8) | data[1];
  // CDR_BE 0, CDR_LE 1 (XCDR1); CDR2_BE 6, CDR2_LE 7 (XCDR2, plain).
  if (id != 0 && id != 1 && id != 6 && id != 7) {
    why_not = "encapsulation " + std::to_string(id) + " is not CDR (0, 1) or plain CDR2 (6, 7)";
    return false;
  }
  const bool little = (id & 1u) != 0;
  const uint32_t xcdr = id >= 6 ? 2 : 1;
  const bool bswap = little != (DDSRT_ENDIAN == DDSRT_LITTLE_ENDIAN);
  const ddsi_sertype_default st = sertype(desc);
  // The payload in 8-byte aligned memory, as Cyclone's serdata keeps it, with 8 bytes of slack
  // and a guard after it: Cyclone 0.10.2's normalize byte-swaps the 8-byte field that straddles
  // the end of a truncated big-endian XCDR2 payload before rejecting it (docs/hardening.md,
  // "Findings"); the slack absorbs that, and a write past it refuses the message.
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
    if (bytes[k] != kPattern) {
      why_not = std::string(kWrotePastThePayload) + " (" + desc.m_typename + ")";
      return false;
    }
  if (!valid) {
    why_not = "malformed or truncated CDR data for " + std::string(desc.m_typename);
    return false;
  }
  dds_istream_t is;
  dds_istream_init(&is, actual, buf.data(), xcdr);
  dds_stream_read_sample(&is, sample, &st);
  dds_istream_fini(&is);
  return true;
}

void free_sample(const dds_topic_descriptor_t& desc, void* sample) {
  dds_sample_free(sample, &desc, DDS_FREE_CONTENTS);
}

std::vector<std::uint8_t> encode(const dds_topic_descriptor_t& desc, const void* sample) {
  const ddsi_sertype_default st = sertype(desc);
  dds_ostreamLE_t os;
  dds_ostreamLE_init(&os, 0, 1);
  dds_stream_write_sampleLE(&os, sample, &st);
  std::vector<std::uint8_t> out(4 + os.x.m_index);
  out[0] = 0;
  out[1] = 1;  // CDR_LE
  std::memcpy(out.data() + 4, os.x.m_buffer, os.x.m_index);
  dds_ostreamLE_fini(&os);
  return out;
}

}  // namespace netvmo::ros
