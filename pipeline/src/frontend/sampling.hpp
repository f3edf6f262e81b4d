// Image sampling shared by the refinement and the frame check (internal to the front end).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

namespace netvmo::frontend::detail {

inline double sample_bilinear(const cv::Mat& g, double x, double y) {
  x = std::clamp(x, 0.0, g.cols - 1.000001);
  y = std::clamp(y, 0.0, g.rows - 1.000001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double ax = x - x0, ay = y - y0;
  const uchar* r0 = g.ptr<uchar>(y0);
  const uchar* r1 = g.ptr<uchar>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) +
         ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

/// Sub-pixel position of the dark-to-bright step along the outward normal n through p: the
/// centroid of the intensity differences in a window re-centred on the estimate (exact for a
/// pixel-integrated straight step edge sampled with bilinear interpolation). Returns false if the
/// step is too weak or the estimate leaves the window; w <= 4.
///
/// `stop_at_peak`: the bright side may be a narrow band in front of something darker (a tag's
/// white margin cut short by the card's edge or a darker background): that band's far edge, a
/// bright-to-dark step within the window, pulls the centroid toward the dark side, by more than
/// 1 px for a band of a quarter cell (tests/pipeline/test_border_check.cpp, narrow quiet zone).
/// Where the intensity beyond the estimate falls from its peak by more than a tenth of the
/// window's range before the window ends, the differences beyond the peak are left out. A
/// window over an isolated edge never falls that far, and gives the same result as without it.
inline bool edge_offset(const cv::Mat& g, cv::Point2d p, cv::Point2d n, double w, double& s_out,
                        bool stop_at_peak = false) {
  constexpr double h = 0.25;
  constexpr int kMaxHalf = 16;  // w <= 4
  const int m = std::min(kMaxHalf, static_cast<int>(std::ceil(w / h)));
  double s0 = 0.0;
  std::array<double, 2 * kMaxHalf + 1> v{};  // v[j + m]: the sample at s0 + j h
  for (int iter = 0; iter < 3; ++iter) {
    for (int j = -m; j <= m; ++j)
      v[static_cast<size_t>(j + m)] =
          sample_bilinear(g, p.x + (s0 + j * h) * n.x, p.y + (s0 + j * h) * n.y);
    int last = m;  // the last sample whose difference counts
    if (stop_at_peak) {
      // The window's range, and the first brightest sample beyond the estimate (j >= 0).
      double lo = v[0], hi = v[0];
      int peak = 0;
      for (int j = -m; j <= m; ++j) {
        const double x = v[static_cast<size_t>(j + m)];
        lo = std::min(lo, x);
        hi = std::max(hi, x);
        if (j > 0 && x > v[static_cast<size_t>(peak + m)]) peak = j;
      }
      if (v[static_cast<size_t>(peak + m)] - v[static_cast<size_t>(2 * m)] > 0.1 * (hi - lo))
        last = peak;
    }
    double sum_g = 0.0, sum_sg = 0.0;
    for (int j = -m + 1; j <= last; ++j) {
      const double s = s0 + j * h;
      const double d = v[static_cast<size_t>(j + m)] - v[static_cast<size_t>(j + m - 1)];
      sum_g += d;
      sum_sg += d * (s - 0.5 * h);
    }
    if (sum_g < 8.0) return false;  // less than 8 gray levels of contrast across the edge
    const double s = sum_sg / sum_g;
    if (std::abs(s) > w + 1.0) return false;
    s0 = s;
  }
  s_out = s0;
  return true;
}

/// Spread of a dark-to-bright edge along the unit normal n through p (p on the edge): the
/// standard deviation of the intensity differences within +-w, sampled every 0.25 px with
/// bilinear interpolation [px]. For a step blurred by a Gaussian of sigma s, integrated over the
/// pixel (variance 1/12 px^2) and interpolated bilinearly (variance 1/6 px^2), it is
/// sqrt(s^2 + 0.25) until the window truncates it. NaN where the differences do not rise.
inline double edge_spread(const cv::Mat& g, cv::Point2d p, cv::Point2d n, double w) {
  constexpr double h = 0.25;
  const int m = static_cast<int>(std::ceil(w / h));
  double sum_g = 0.0, sum_sg = 0.0, sum_ssg = 0.0;
  double prev = sample_bilinear(g, p.x - m * h * n.x, p.y - m * h * n.y);
  for (int j = -m + 1; j <= m; ++j) {
    const double cur = sample_bilinear(g, p.x + j * h * n.x, p.y + j * h * n.y);
    const double d = cur - prev, s = (j - 0.5) * h;
    sum_g += d;
    sum_sg += d * s;
    sum_ssg += d * s * s;
    prev = cur;
  }
  if (!(sum_g > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double c = sum_sg / sum_g;
  return std::sqrt(std::max(0.0, sum_ssg / sum_g - c * c));
}

/// The intersection of the lines a1 + t d1 and a2 + s d2; nullopt where they are parallel to
/// 1e-6 (|d1 x d2| below 1e-6 |d1| |d2|).
inline std::optional<cv::Point2d> intersect_lines(cv::Point2d a1, cv::Point2d d1, cv::Point2d a2,
                                                  cv::Point2d d2) {
  const double det = d1.x * (-d2.y) - d1.y * (-d2.x);
  if (std::abs(det) < 1e-6 * cv::norm(d1) * cv::norm(d2)) return std::nullopt;
  const double rx = a2.x - a1.x, ry = a2.y - a1.y;
  const double t = (rx * (-d2.y) - ry * (-d2.x)) / det;
  return cv::Point2d(a1.x + t * d1.x, a1.y + t * d1.y);
}

inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
  const double hi = v[h];
  if (v.size() % 2) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h)));
}

inline bool inside(const cv::Mat& g, cv::Point2d p) {
  return p.x >= 0.0 && p.y >= 0.0 && p.x <= g.cols - 1.0 && p.y <= g.rows - 1.0;
}

}  // namespace netvmo::frontend::detail
