// Fuzz target: the JPEG marker walk that tells a JPEG cut short (io/image_file.hpp,
// jpeg_cut_short), on any bytes. It must stay inside them and find a cut only in data that starts
// with SOI; and it takes a JPEG for complete only at an EOI marker, so where it takes the data for
// complete, a shorter part of it (half, all but the last two bytes) is complete only if it holds
// the bytes FF D9 itself.
#include <cstdint>
#include <string>

#include "netvmo/pipeline/io/image_file.hpp"

namespace {
bool holds_eoi(const std::uint8_t* d, std::size_t n) {
  for (std::size_t i = 0; i + 1 < n; ++i)
    if (d[i] == 0xFF && d[i + 1] == 0xD9) return true;
  return false;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string why = netvmo::io::jpeg_cut_short(data, size);
  const bool soi = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;
  if (!why.empty() && !soi) __builtin_trap();
  if (why.empty() && soi) {
    if (!holds_eoi(data, size)) __builtin_trap();
    for (std::size_t n : {size / 2, size - 2})
      if (n >= 2 && netvmo::io::jpeg_cut_short(data, n).empty() && !holds_eoi(data, n))
        __builtin_trap();
  }
  return 0;
}
