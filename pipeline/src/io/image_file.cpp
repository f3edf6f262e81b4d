#include "netvmo/pipeline/io/image_file.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {
constexpr std::uint8_t kSOI = 0xD8, kEOI = 0xD9, kSOS = 0xDA, kTEM = 0x01;
bool restart(std::uint8_t m) {  // RST0..RST7: no length, also inside a scan's data
  return m >= 0xD0 && m <= 0xD7;
}
std::string marker_name(std::uint8_t m) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "FF%02X", m);
  return buf;
}
}  // namespace

std::string jpeg_cut_short(const std::uint8_t* d, std::size_t n) {
  if (n < 2 || d[0] != 0xFF || d[1] != kSOI) return {};
  const auto ends = [n](const std::string& where) {
    return "the data ends at byte " + std::to_string(n) + where + ", without an EOI marker";
  };
  std::size_t i = 2;
  int scans = 0;
  for (;;) {
    // The next marker: FF, any fill bytes FF, its code (B.1.1.2). Bytes before it that are not
    // FF are skipped, as libjpeg skips them (with a warning of its own).
    while (i < n && d[i] != 0xFF) ++i;
    while (i < n && d[i] == 0xFF) ++i;
    if (i >= n) return ends(scans == 0 ? " before any scan (no image data)" : "");
    const std::uint8_t m = d[i++];
    if (m == kEOI) return {};
    if (m == 0x00 || m == kTEM || m == kSOI || restart(m)) continue;  // no length
    // A marker segment: its length counts its own two bytes (B.1.1.4).
    const std::size_t start = i - 2;
    if (n - i < 2)
      return ends(" inside the marker segment " + marker_name(m) + " at byte " +
                  std::to_string(start));
    const std::size_t length = (std::size_t{d[i]} << 8) | d[i + 1];
    if (length < 2) continue;  // not a segment: the decoder will say what it makes of it
    if (n - i < length)
      return ends(" inside the marker segment " + marker_name(m) + " at byte " +
                  std::to_string(start));
    i += length;
    if (m != kSOS) continue;
    // A scan's entropy-coded data (B.1.1.5): up to the next marker other than RSTn; FF 00 is a
    // stuffed data byte FF.
    ++scans;
    for (;;) {
      const void* ff = i < n ? std::memchr(d + i, 0xFF, n - i) : nullptr;
      if (!ff) return ends(" inside scan " + std::to_string(scans) + "'s entropy-coded data");
      std::size_t j = static_cast<std::size_t>(static_cast<const std::uint8_t*>(ff) - d) + 1;
      while (j < n && d[j] == 0xFF) ++j;
      if (j >= n) return ends(" inside scan " + std::to_string(scans) + "'s entropy-coded data");
      if (d[j] == 0x00 || restart(d[j])) {
        i = j + 1;
        continue;
      }
      i = j - 1;  // the FF of a marker: the outer loop reads it
      break;
    }
  }
}

cv::Mat read_gray_image(const fs::path& file) {
  // A JPEG (it starts with SOI) is checked before it is decoded. Most end with EOI, which two
  // bytes at the end tell; the others (cut short, or bytes after the EOI) are read whole.
  if (std::ifstream in{file, std::ios::binary}) {
    char head[2] = {0, 0}, tail[2] = {0, 0};
    if (in.read(head, 2) && static_cast<std::uint8_t>(head[0]) == 0xFF &&
        static_cast<std::uint8_t>(head[1]) == kSOI && in.seekg(-2, std::ios::end) &&
        in.read(tail, 2) &&
        !(static_cast<std::uint8_t>(tail[0]) == 0xFF &&
          static_cast<std::uint8_t>(tail[1]) == kEOI)) {
      in.clear();
      in.seekg(0, std::ios::end);
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(in.tellg()));
      in.seekg(0);
      in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
      if (in) {
        const std::string why = jpeg_cut_short(bytes.data(), bytes.size());
        if (!why.empty()) throw InputError(file.string() + ": JPEG cut short: " + why);
      }
    }
  }
  cv::Mat m;
  try {
    m = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    throw InputError(file.string() + ": cannot read image: " + e.err);
  }
  if (m.empty())
    throw InputError(file.string() + ": cannot read image (unreadable, corrupt or not an image)");
  return m;
}

}  // namespace netvmo::io
