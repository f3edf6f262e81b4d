#include "stream_util.hpp"

#include <algorithm>
#include <cctype>
#include <opencv2/imgproc.hpp>

namespace netvmo::sources::detail {

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
}

cv::Mat to_gray(const cv::Mat& m) {
  if (m.empty() || m.type() == CV_8UC1) return m;
  cv::Mat g;
  if (m.channels() == 3)
    cv::cvtColor(m, g, cv::COLOR_BGR2GRAY);
  else if (m.channels() == 4)
    cv::cvtColor(m, g, cv::COLOR_BGRA2GRAY);
  else
    g = m;
  if (g.depth() != CV_8U) g.convertTo(g, CV_8U, g.depth() == CV_16U ? 1.0 / 257.0 : 1.0);
  return g;
}

}  // namespace netvmo::sources::detail
