// Helpers shared by the camera stream kinds and the dataset reader (private to sources/).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace netvmo::sources::detail {

/// Non-empty and only decimal digits.
bool all_digits(const std::string& s);
/// 8-bit single-channel view or copy of an image (BGR, BGRA, 16-bit converted).
cv::Mat to_gray(const cv::Mat& m);

}  // namespace netvmo::sources::detail
