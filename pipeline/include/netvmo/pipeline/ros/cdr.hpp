// ROS 2 messages as bytes: the CDR serialization a rosbag2 bag stores and DDS carries (a 4-byte
// encapsulation header, then XCDR1 or XCDR2 plain data), read and written with Cyclone DDS's own
// CDR stream functions and the type descriptors idlc generates from pipeline/idl/.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <string>
#include <vector>

namespace netvmo::ros {

/// The start of decode()'s why_not when Cyclone's normalize wrote beyond the payload's 8 bytes
/// of slack (a defect of the middleware that a fuzzer must see).
inline constexpr const char* kWrotePastThePayload =
    "Cyclone DDS's normalize wrote past the payload";

/// Reads a serialized message of type `desc` into `sample` (zeroed first) as Cyclone DDS's receive
/// path does: checks and byte-swaps the payload (dds_stream_normalize), then reads it
/// (dds_stream_read_sample), which allocates its strings and sequences. Encapsulations CDR_BE,
/// CDR_LE (XCDR1), CDR2_BE and CDR2_LE (XCDR2, plain), the encodings of a @final type; bytes after
/// the message are ignored. Returns false, with why_not saying why, for anything else or a
/// malformed payload (then `sample` holds nothing to free). After true, free_sample() it.
bool decode(const dds_topic_descriptor_t& desc, const std::uint8_t* data, std::size_t size,
            void* sample, std::string& why_not);
/// Frees what decode() allocated inside `sample`.
void free_sample(const dds_topic_descriptor_t& desc, void* sample);
/// `sample` serialized as CDR_LE (XCDR1, little-endian: what ROS 2 writes), with its 4-byte
/// encapsulation header.
std::vector<std::uint8_t> encode(const dds_topic_descriptor_t& desc, const void* sample);

/// A decoded message that frees itself: T is an idlc-generated struct, `desc` its descriptor.
template <class T>
class Decoded {
 public:
  explicit Decoded(const dds_topic_descriptor_t& desc) : desc_(desc) {}
  Decoded(const Decoded&) = delete;
  Decoded& operator=(const Decoded&) = delete;
  ~Decoded() {
    if (ok_) free_sample(desc_, &value_);
  }
  /// decode() into this object (freeing what it held).
  bool read(const std::uint8_t* data, std::size_t size, std::string& why_not) {
    if (ok_) free_sample(desc_, &value_);
    ok_ = decode(desc_, data, size, &value_, why_not);
    return ok_;
  }
  const T& operator*() const { return value_; }
  const T* operator->() const { return &value_; }

 private:
  const dds_topic_descriptor_t& desc_;
  T value_{};
  bool ok_ = false;
};

}  // namespace netvmo::ros
