// Image files and encoded images read as 8-bit gray with OpenCV's imgcodecs, and the one check
// OpenCV leaves out: a JPEG cut short (a recording or a copy interrupted, a message truncated) is
// decoded by libjpeg with the rest of the image filled gray, and only a warning without the
// file's name on stderr ("Premature end of JPEG file"); a PNG cut short fails with libpng's own
// line on stderr. Here both are checked before decoding: one InputError naming the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace netvmo::io {

/// The image files netvmo reads, by extension (any case), as a message names them.
inline constexpr const char* kImageExtensions = "png, jpg, jpeg, pgm, bmp, tif, tiff";

/// Whether `file`'s extension, in any case, is one of kImageExtensions.
bool is_image_file(const std::filesystem::path& file);

/// Every regular file below `root` (recursively) that is_image_file, sorted by path; InputError
/// naming `root` when it is not a folder or cannot be listed.
std::vector<std::filesystem::path> list_images(const std::filesystem::path& root);

/// Whether the JPEG stream data[0, size) ends before its EOI marker, and where: "" when it is
/// not a JPEG (it does not start with the SOI marker FF D8) or its markers lead to an EOI marker
/// (ITU-T T.81, B.1.1: each marker segment skipped by its length, each scan's entropy-coded data
/// read up to the next marker that is not RSTn, fill bytes FF and stuffed FF 00 skipped; bytes
/// after the EOI, such as a trailer, do not count); else where the data ends ("the data ends
/// at byte 500 inside scan 1's entropy-coded data, without an EOI marker").
std::string jpeg_cut_short(const std::uint8_t* data, std::size_t size);

/// Whether the PNG data[0, size) ends before its IEND chunk, and where: "" when it is not a PNG
/// (no PNG signature) or its chunks (length, type, data, CRC) lead to IEND; else where the data
/// ends ("the data ends at byte 700 inside the IDAT chunk at byte 91, without an IEND chunk").
std::string png_cut_short(const std::uint8_t* data, std::size_t size);

/// "JPEG cut short: " + jpeg_cut_short, or "PNG cut short: " + png_cut_short, or "".
std::string image_cut_short(const std::uint8_t* data, std::size_t size);

/// The image file as 8-bit gray (cv::imread, IMREAD_GRAYSCALE); InputError naming the file when
/// it cannot be read or decoded, or is a JPEG or PNG cut short (image_cut_short; checked before it
/// is decoded, so libjpeg and libpng print nothing).
cv::Mat read_gray_image(const std::filesystem::path& file);

}  // namespace netvmo::io
