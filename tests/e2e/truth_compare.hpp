// Comparing the front end's corners with the renderer's ground truth (e2e tests).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "netvmo/render/renderer.hpp"

namespace netvmo::testing {

/// Largest distance of a detected corner from the truth [px] (infinite without truth).
inline double max_corner_error(const std::array<cv::Point2d, 4>& c, const render::FrameTruth& t) {
  double e = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    if (!t.corners[k]) return std::numeric_limits<double>::infinity();
    e = std::max(e, std::hypot(c[k].x - t.corners[k]->x(), c[k].y - t.corners[k]->y()));
  }
  return e;
}

/// Shortest side of the projected black square [px], 0 when not in view.
inline double narrowest_side(const render::FrameTruth& t) {
  if (!t.in_fov) return 0.0;
  double side = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < 4; ++k)
    side = std::min(side, (*t.corners[k] - *t.corners[(k + 1) % 4]).norm());
  return side;
}

}  // namespace netvmo::testing
