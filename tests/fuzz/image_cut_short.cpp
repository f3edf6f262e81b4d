// Fuzz target: the walks that tell a JPEG or PNG cut short (io/image_file.hpp,
// io::image_cut_short: JPEG markers to EOI, PNG chunks to IEND), on any bytes. They must stay
// inside them and find a cut only in data that starts with the format's signature. A JPEG walk
// takes data for complete only at an EOI marker, so JPEG data taken for complete holds the bytes
// FF D9, and so does a shorter part of it (half, all but the last two bytes) taken for complete.
// (A PNG walk also stops, without an answer, at a chunk length above 2^31 - 1, which no PNG has:
// the decoder then fails on its own; so the same does not hold for PNG.)
#include <cstdint>
#include <cstring>
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
  using netvmo::io::jpeg_cut_short;
  const bool jpeg = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;
  const bool png = size >= 8 && std::memcmp(data, "\x89PNG\r\n\x1A\n", 8) == 0;
  if (!netvmo::io::png_cut_short(data, size).empty() && !png) __builtin_trap();
  const std::string why = jpeg_cut_short(data, size);
  if (!why.empty() && !jpeg) __builtin_trap();
  if (!netvmo::io::image_cut_short(data, size).empty() && !jpeg && !png) __builtin_trap();
  if (jpeg && why.empty()) {
    if (!holds_eoi(data, size)) __builtin_trap();
    for (std::size_t n : {size / 2, size - 2})
      if (n >= 2 && jpeg_cut_short(data, n).empty() && !holds_eoi(data, n)) __builtin_trap();
  }
  return 0;
}
