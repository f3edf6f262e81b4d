#include "netvmo/pipeline/io/image_file.hpp"

#include <algorithm>
#include <cctype>
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
constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
// The IEND chunk: length 0, type, CRC.
constexpr std::uint8_t kPngEnd[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
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

std::string png_cut_short(const std::uint8_t* d, std::size_t n) {
  if (n < sizeof kPngSignature || std::memcmp(d, kPngSignature, sizeof kPngSignature) != 0)
    return {};
  const auto ends = [n](const std::string& where) {
    return "the data ends at byte " + std::to_string(n) + where + ", without an IEND chunk";
  };
  // Chunks: length (4 bytes, big-endian, at most 2^31 - 1), type (4), data, CRC (4).
  for (std::size_t i = sizeof kPngSignature; i < n;) {
    if (n - i < 8) return ends(" inside a chunk's length and type at byte " + std::to_string(i));
    const std::uint32_t length = (std::uint32_t{d[i]} << 24) | (std::uint32_t{d[i + 1]} << 16) |
                                 (std::uint32_t{d[i + 2]} << 8) | d[i + 3];
    std::string type(reinterpret_cast<const char*>(d + i + 4), 4);  // letters in a PNG
    const auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); };
    if (!std::all_of(type.begin(), type.end(), letter)) type = "(not a chunk type)";
    if (length > 0x7FFFFFFFu)
      return {};  // not a PNG chunk: the decoder will say what it makes of it
    if (n - i - 8 < std::size_t{length} + 4)
      return ends(" inside the " + type + " chunk at byte " + std::to_string(i));
    i += 12 + std::size_t{length};
    if (type == "IEND") return {};
  }
  return ends("");
}

bool is_image_file(const fs::path& file) {
  std::string e = file.extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".pgm" || e == ".bmp" || e == ".tif" ||
         e == ".tiff";
}

std::vector<fs::path> list_images(const fs::path& root) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw InputError(root.string() + ": not a folder of images");
  std::vector<fs::path> files;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->is_regular_file(ec) && is_image_file(it->path())) files.push_back(it->path());
  if (ec) throw InputError(root.string() + ": cannot list the folder: " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

std::string image_cut_short(const std::uint8_t* data, std::size_t size) {
  if (std::string why = jpeg_cut_short(data, size); !why.empty()) return "JPEG cut short: " + why;
  if (std::string why = png_cut_short(data, size); !why.empty()) return "PNG cut short: " + why;
  return {};
}

cv::Mat read_gray_image(const fs::path& file) {
  // The file is read once and decoded from memory (cv::imdecode: what cv::imread does with the
  // file, EXIF orientation included). A JPEG or PNG is checked first: most end with their last
  // marker or chunk (EOI; IEND, whose 12 bytes are always the same), which their last bytes tell;
  // the others (cut short, or bytes after the end) are walked.
  std::vector<std::uint8_t> bytes;
  if (std::ifstream in{file, std::ios::binary | std::ios::ate}) {
    const std::streamoff size = in.tellg();  // -1 where it has no size (not a regular file)
    if (size > 0) {
      bytes.resize(static_cast<std::size_t>(size));
      in.seekg(0);
      if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) bytes.clear();
    }
  }
  const std::size_t n = bytes.size();
  const bool jpeg_end = n >= 2 && bytes[n - 2] == 0xFF && bytes[n - 1] == kEOI;
  const bool png_end =
      n >= sizeof kPngEnd && std::memcmp(&bytes[n - sizeof kPngEnd], kPngEnd, sizeof kPngEnd) == 0;
  if (!jpeg_end && !png_end)
    if (const std::string why = image_cut_short(bytes.data(), n); !why.empty())
      throw InputError(file.string() + ": " + why);
  cv::Mat m;
  try {
    if (n > 0) m = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    throw InputError(file.string() + ": cannot read image: " + e.err);
  }
  if (m.empty())
    throw InputError(file.string() + ": cannot read image (unreadable, corrupt or not an image)");
  return m;
}

}  // namespace netvmo::io
