#include "netvmo/pipeline/frontend/resampling.hpp"

#include <cstdio>

namespace netvmo::frontend {
namespace {

// Pixels a, b, c, d in a line: (b, c) is a pair on a steep edge when a -> b and c -> d step the
// same way by at least `step`.
struct PairCount {
  long pairs = 0, equal = 0;
  void add(int a, int b, int c, int d, int step) {
    const int before = b - a, after = d - c;
    if ((before >= step && after >= step) || (before <= -step && after <= -step)) {
      ++pairs;
      equal += b == c;
    }
  }
};

}  // namespace

Resampling measure_resampling(const cv::Mat& gray, const ResamplingSettings& s) {
  CV_Assert(gray.type() == CV_8UC1);
  PairCount n;
  for (int r = 0; r < gray.rows; ++r) {
    const uchar* p = gray.ptr<uchar>(r);
    for (int c = 0; c + 3 < gray.cols; ++c) n.add(p[c], p[c + 1], p[c + 2], p[c + 3], s.min_step);
  }
  for (int r = 0; r + 3 < gray.rows; ++r) {
    const uchar *p0 = gray.ptr<uchar>(r), *p1 = gray.ptr<uchar>(r + 1),
                *p2 = gray.ptr<uchar>(r + 2), *p3 = gray.ptr<uchar>(r + 3);
    for (int c = 0; c < gray.cols; ++c) n.add(p0[c], p1[c], p2[c], p3[c], s.min_step);
  }
  Resampling out;
  out.pairs = n.pairs;
  out.repeated = n.pairs > 0 ? static_cast<double>(n.equal) / static_cast<double>(n.pairs) : 0.0;
  out.nearest_neighbour = n.pairs >= s.min_pairs && out.repeated > s.max_repeated;
  return out;
}

std::optional<std::string> resampling_warning(int camera_id, const Resampling& r) {
  if (!r.nearest_neighbour) return std::nullopt;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "camera %d: its images look resampled by nearest neighbour (%.0f %% of %ld pixel "
                "pairs on steep edges repeated in its first image; give raw frames with their "
                "calibration): %s",
                camera_id, 100.0 * r.repeated, r.pairs, kResamplingConsequence);
  return std::string(buf);
}

}  // namespace netvmo::frontend
