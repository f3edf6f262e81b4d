#include "netvmo/pipeline/frontend/front_end.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "netvmo/pipeline/error.hpp"

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

/// Keeps the more informative of two results: a detection, else a rejection with a reason
/// other than not_found, else the first.
void keep_best(FrameDetections& best, FrameDetections&& next) {
  const auto rank = [](TargetStatus s) {
    return s == TargetStatus::detected ? 2 : s == TargetStatus::not_found ? 0 : 1;
  };
  if (rank(next.status) > rank(best.status)) best = std::move(next);
}
}  // namespace

double narrowest_side(const std::array<cv::Point2d, 4>& c) {
  double m = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < 4; ++k) m = std::min(m, cv::norm(c[(k + 1) % 4] - c[k]));
  return m;
}

void validate(const TrackingSettings& t) {
  auto bad = [](const std::string& what) { throw InputError("tracking settings: " + what); };
  if (!(t.window_margin >= 0.0)) bad("window_margin must be >= 0");
  if (t.window_pad < 0) bad("window_pad must be >= 0");
  if (t.full_frame_every < 1) bad("full_frame_every must be >= 1");
  if (!(t.full_res_below_px >= 0.0)) bad("full_res_below_px must be >= 0");
  if (t.acquire_every < 0) bad("acquire_every must be >= 0 (0: no acquisition pass)");
}

FrontEnd::FrontEnd(DetectorSettings settings, TrackingSettings tracking)
    : detector_(std::move(settings)), tracking_(tracking) {
  validate(tracking_);
}

TagObservation FrontEnd::observe(const cv::Mat& gray, const io::Calibration& calib,
                                 FrameDetections* all, TrackState* track) {
  TagObservation obs;
  FrameDetections dets;
  unsigned searches = 0, found_by = 0;
  if (gray.empty()) {
    dets.status = TargetStatus::no_image;
    dets.reason = "no image (camera blind in this frame)";
  } else {
    const bool tracked = track && tracking_.enabled && track->last;
    auto found = [&] { return dets.status == TargetStatus::detected; };
    auto search = [&](unsigned what, const cv::Rect& region, const SearchOptions& opt) {
      // A duplicate is final: a later, narrower search (the window) must not pick one of them.
      if (found() || dets.status == TargetStatus::duplicate_id) return;
      const bool first = searches == 0;
      searches |= what;
      FrameDetections d = detector_.detect(gray, region, &calib, opt);
      if (d.status == TargetStatus::detected) found_by = what;
      if (first)
        dets = std::move(d);
      else
        keep_best(dets, std::move(d));
    };
    auto window = [&] {
      const auto& last = *track->last;
      const cv::Rect w = tracking_window(last, tracking_);
      const double side = narrowest_side(last);
      SearchOptions opt;
      if (side < tracking_.full_res_below_px) opt.decimate = 1.0;
      search(kSearchWindow, w, opt);
      if (tracking_.shadow_retry) {
        // White level over 4 bit cells of the last tag: wider than its dark runs, narrower than
        // a shadow band across it (a wider closing fills the band in).
        opt.normalized = true;
        opt.normalize_window =
            std::max(5, static_cast<int>(std::lround(4.0 * side / detector_.border_cells())));
        search(kSearchNormalizedWindow, w, opt);
      }
    };
    const cv::Rect whole(0, 0, gray.cols, gray.rows);
    const bool periodic_full =
        tracked && track->frames_since_full + 1 >= tracking_.full_frame_every;
    if (tracked && !periodic_full) window();
    if (!found()) {
      search(kSearchFullFrame, whole, {});
      if (track) track->frames_since_full = 0;
    } else {
      ++track->frames_since_full;
    }
    if (tracked && periodic_full) window();
    // Acquisition: a blind camera's every acquire_every-th frame at full resolution.
    if (track && tracking_.enabled && !tracked && tracking_.acquire_every > 0 &&
        track->blind_frames % tracking_.acquire_every == 0 &&
        detector_.settings().quad_decimate > 1.0) {
      SearchOptions opt;
      opt.decimate = 1.0;
      search(kSearchAcquisition, whole, opt);
    }
  }
  if (track) {
    track->searches = searches;
    track->found_by = found_by;
    if (const TagDetection* t = dets.target()) {
      track->last = t->corners;
      track->blind_frames = 0;
    } else {
      track->last.reset();
      ++track->blind_frames;
    }
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
