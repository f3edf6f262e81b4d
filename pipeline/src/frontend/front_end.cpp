#include "netvmo/pipeline/frontend/front_end.hpp"

#include <algorithm>

namespace netvmo::frontend {

Eigen::Matrix<double, 8, 1> normalized_features(const std::array<cv::Point2d, 4>& corners_px,
                                                const io::Calibration& calib) {
  const auto xy =
      io::normalize_points(std::vector<cv::Point2d>(corners_px.begin(), corners_px.end()), calib);
  Eigen::Matrix<double, 8, 1> f;
  for (int k = 0; k < 4; ++k) {
    f[2 * k] = xy[static_cast<size_t>(k)].x;
    f[2 * k + 1] = xy[static_cast<size_t>(k)].y;
  }
  return f;
}

namespace {
cv::Rect tracking_window(const std::array<cv::Point2d, 4>& c, const TrackingSettings& t) {
  double x0 = c[0].x, x1 = c[0].x, y0 = c[0].y, y1 = c[0].y;
  for (const auto& p : c) {
    x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  }
  const double grow = t.window_margin * std::max(x1 - x0, y1 - y0) + t.window_pad;
  return cv::Rect(cv::Point(cvFloor(x0 - grow), cvFloor(y0 - grow)),
                  cv::Point(cvCeil(x1 + grow) + 1, cvCeil(y1 + grow) + 1));
}
}  // namespace

TagObservation FrontEnd::observe(const cv::Mat& gray, const io::Calibration& calib,
                                 FrameDetections* all, TrackState* track) {
  TagObservation obs;
  FrameDetections dets;
  if (gray.empty()) {
    dets.status = TargetStatus::no_image;
    dets.reason = "no image (camera blind in this frame)";
  } else {
    const bool windowed = track && tracking_.enabled && track->last &&
                          track->frames_since_full + 1 < tracking_.full_frame_every;
    if (windowed) {
      dets = detector_.detect(gray, tracking_window(*track->last, tracking_), &calib);
      ++track->frames_since_full;
    }
    if (!windowed || dets.status != TargetStatus::detected) {
      dets = detector_.detect(gray, &calib);
      if (track) track->frames_since_full = 0;
    }
  }
  if (track) {
    if (const TagDetection* t = dets.target())
      track->last = t->corners;
    else
      track->last.reset();
  }
  obs.status = dets.status;
  obs.reason = dets.reason;
  if (const TagDetection* t = dets.target()) {
    obs.delta = true;
    obs.tag_id = t->id;
    obs.hamming = t->hamming;
    obs.margin = t->margin;
    obs.corners_px = t->corners;
    obs.f_normalized = normalized_features(t->corners, calib);
  }
  if (all) *all = std::move(dets);
  return obs;
}

}  // namespace netvmo::frontend
