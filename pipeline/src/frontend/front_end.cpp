#include "netvmo/pipeline/frontend/front_end.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>

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

CornerCovariance normalized_covariance(const TagDetection& t, const io::Calibration& calib,
                                       const DetectorSettings& s) {
  const CornerCovariance px = t.corner_covariance
                                  ? *t.corner_covariance
                                  : CornerCovariance(CornerCovariance::Identity() *
                                                     (s.corner_sigma_px * s.corner_sigma_px));
  Eigen::Matrix2d K;
  K << calib.K(0, 0), calib.K(0, 1), 0.0, calib.K(1, 1);
  const Eigen::Matrix2d A = K.inverse();
  CornerCovariance T = CornerCovariance::Zero();
  for (int k = 0; k < 4; ++k) T.block<2, 2>(2 * k, 2 * k) = A;
  return T * px * T.transpose();
}

std::optional<Eigen::MatrixXd> f_covariance_matrix(const Observation& obs) {
  const Eigen::Index n = obs.f_normalized.size();
  if (n != 8 * static_cast<Eigen::Index>(obs.f_covariance.size())) return std::nullopt;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  for (size_t q = 0; q < obs.f_covariance.size(); ++q)
    C.block<8, 8>(8 * static_cast<Eigen::Index>(q), 8 * static_cast<Eigen::Index>(q)) =
        obs.f_covariance[q];
  return C;
}

void set_target(DetectorSettings& s, const io::TargetConfig& target) {
  set_targets(s, {target});
}

void set_targets(DetectorSettings& s, const std::vector<io::TargetConfig>& targets) {
  s.family = targets.at(0).family;
  s.target_id = targets[0].id;
  s.bundle_ids.clear();
  s.tags_per_target.clear();
  for (const auto& t : targets) {
    for (size_t k = 0; k < t.tag_count(); ++k)
      if (&t != &targets[0] || k > 0) s.bundle_ids.push_back(t.tag_id(k));
    if (targets.size() > 1) s.tags_per_target.push_back(static_cast<int>(t.tag_count()));
  }
}

obs::FeatureModel tag_points(const io::TargetConfig& target, const std::vector<int>& slots) {
  obs::FeatureModel m;
  for (int k : slots) {
    const auto sq = obs::FeatureModel::square(target.tag_size(static_cast<size_t>(k)));
    const obs::SE3 g_ot = target.tag_pose(static_cast<size_t>(k));
    for (const auto& p : sq.points_o) m.points_o.push_back(g_ot * p);
  }
  return m;
}

obs::FeatureModel observation_model(const io::TargetConfig& target, const Observation& o) {
  if (target.bundle.empty()) return obs::FeatureModel::square(target.size);
  return tag_points(target, o.slots);
}

namespace {
/// The search window around the last tags: their corners' bounding box grown by window_margin
/// x the box's size plus window_pad.
cv::Rect tracking_window(const std::vector<std::array<cv::Point2d, 4>>& tags,
                         const TrackingSettings& t) {
  double x0 = tags[0][0].x, x1 = x0, y0 = tags[0][0].y, y1 = y0;
  for (const auto& c : tags)
    for (const auto& p : c) {
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
      y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
  const double grow = t.window_margin * std::max(x1 - x0, y1 - y0) + t.window_pad;
  return cv::Rect(cv::Point(cvFloor(x0 - grow), cvFloor(y0 - grow)),
                  cv::Point(cvCeil(x1 + grow) + 1, cvCeil(y1 + grow) + 1));
}

int rank(TargetStatus s) {
  return s == TargetStatus::detected ? 2 : s == TargetStatus::not_found ? 0 : 1;
}

/// Keeps, per target, the more informative of two searches' results: a detection, else a
/// rejection with a reason other than not_found, else the first. When the later search is
/// better for every target it replaces the result (a single target's searches never mix); else
/// its tags are appended to `all` and the targets it decided better take its decisions.
void keep_best(FrameDetections& best, FrameDetections&& next) {
  std::vector<bool> take(best.targets.size());
  size_t taken = 0;
  for (size_t j = 0; j < take.size(); ++j) {
    take[j] = rank(next.targets[j].status) > rank(best.targets[j].status);
    taken += take[j];
  }
  if (taken == 0) return;
  if (taken == take.size()) {
    best = std::move(next);
    return;
  }
  const int offset = static_cast<int>(best.all.size());
  best.all.insert(best.all.end(), next.all.begin(), next.all.end());
  for (size_t j = 0; j < take.size(); ++j) {
    if (!take[j]) continue;
    const TargetDecision& t = next.targets[j];
    for (size_t k = t.first_tag; k < t.first_tag + t.tag_count; ++k) {
      best.tags[k] = next.tags[k];
      if (best.tags[k].index >= 0) best.tags[k].index += offset;
    }
    best.targets[j] = t;
  }
  best.target_index = best.tags[0].index;
  best.status = best.targets[0].status;
  best.reason = best.targets[0].reason;
}

/// Every target detected (the searches may stop), or each either detected or rejected as a
/// duplicate (final: a later, narrower search must not pick one of the duplicates).
bool all_found(const FrameDetections& d) {
  if (d.targets.empty()) return false;
  for (const auto& t : d.targets)
    if (t.status != TargetStatus::detected) return false;
  return true;
}
bool settled(const FrameDetections& d) {
  if (d.targets.empty()) return false;
  for (const auto& t : d.targets)
    if (t.status != TargetStatus::detected && t.status != TargetStatus::duplicate_id) return false;
  return true;
}
}  // namespace

void validate(const TrackingSettings& t) {
  auto bad = [](const std::string& what) { throw InputError("tracking settings: " + what); };
  if (!(t.window_margin >= 0.0)) bad("window_margin must be >= 0");
  if (t.window_pad < 0) bad("window_pad must be >= 0");
  if (t.full_frame_every < 1) bad("full_frame_every must be >= 1");
  if (!(t.full_res_below_px >= 0.0)) bad("full_res_below_px must be >= 0");
  if (t.window_max_decimate < 1) bad("window_max_decimate must be >= 1");
  if (t.acquire_every < 0) bad("acquire_every must be >= 0 (0: no acquisition pass)");
  if (t.change_dn < 0 || t.change_dn > 255) bad("change_dn must be 0..255");
  if (t.change_pixels < 0) bad("change_pixels must be >= 0 (0: always search)");
}

double window_decimate(double side, double quad_decimate, const TrackingSettings& t) {
  if (side < t.full_res_below_px) return 1.0;
  if (!(t.full_res_below_px > 0.0) || t.window_max_decimate <= quad_decimate) return quad_decimate;
  const double d = std::floor(quad_decimate * side / t.full_res_below_px);
  return std::clamp(d, quad_decimate, static_cast<double>(t.window_max_decimate));
}

FrontEnd::FrontEnd(DetectorSettings settings, TrackingSettings tracking,
                   std::shared_ptr<const TagDecoder> decoder)
    : detector_(std::move(settings), std::move(decoder)), tracking_(tracking) {
  validate(tracking_);
}

namespace {
ChangeReference change_reference(const cv::Mat& gray) {
  ChangeReference r;
  const cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::erode(gray, r.low, k);
  cv::dilate(gray, r.high, k);
  return r;
}
}  // namespace

bool FrontEnd::unchanged(const cv::Mat& gray, const ChangeReference& reference) {
  if (tracking_.change_pixels <= 0 || reference.empty() || gray.size() != reference.low.size() ||
      gray.type() != reference.low.type())
    return false;
  // Saturating differences: how far each pixel lies above the range, then below it.
  int changed = 0;
  for (int side = 0; side < 2; ++side) {
    if (side == 0)
      cv::subtract(gray, reference.high, difference_);
    else
      cv::subtract(reference.low, gray, difference_);
    cv::threshold(difference_, difference_, tracking_.change_dn, 255, cv::THRESH_BINARY);
    changed += cv::countNonZero(difference_.reshape(1));
    if (changed >= tracking_.change_pixels) return false;
  }
  return true;
}

Observation FrontEnd::observe(const cv::Mat& gray, const io::Calibration& calib,
                              FrameDetections* all, TrackState* track) {
  return std::move(observe_targets(gray, calib, all, track).front());
}

std::vector<Observation> FrontEnd::observe_targets(const cv::Mat& gray,
                                                   const io::Calibration& calib,
                                                   FrameDetections* all, TrackState* track) {
  FrameDetections dets;
  unsigned searches = 0, found_by = 0;
  double window_d = 0.0;  // TrackState::window_decimate
  if (gray.empty()) {
    dets.status = TargetStatus::no_image;
    dets.reason = "no image (camera blind in this frame)";
    for (size_t j = 0; j < target_count(); ++j)
      dets.targets.push_back({TargetStatus::no_image, dets.reason, 0, 0});
  } else {
    const bool tracked = track && tracking_.enabled && !track->last_all.empty();
    // Not tracked, but the last frame decoded a target's tag that the frame check rejected.
    const bool seen = track && tracking_.enabled && !tracked && !track->last_seen.empty();
    // This frame's ChangeReference, made once (the whole-image search and the acquisition pass
    // may both keep it; cv::Mat shares the pixels).
    std::optional<ChangeReference> reference;
    const auto this_reference = [&]() -> const ChangeReference& {
      if (!reference) reference = change_reference(gray);
      return *reference;
    };
    bool merged = false;
    // A search's result joins the frame's (the first one is the frame's).
    auto merge = [&](unsigned what, FrameDetections&& d) {
      if (all_found(d)) found_by = what;
      if (!merged)
        dets = std::move(d);
      else
        keep_best(dets, std::move(d));
      merged = true;
    };
    auto search = [&](unsigned what, const cv::Rect& region, const SearchSettings& opt) {
      if (settled(dets)) return;
      searches |= what;
      merge(what, detector_.detect(gray, region, &calib, opt));
    };
    auto window = [&] {
      const auto& last = tracked ? track->last_all : track->last_seen;
      const cv::Rect w = tracking_window(last, tracking_);
      double side = narrowest_side(last[0]);
      for (const auto& c : last) side = std::min(side, narrowest_side(c));
      SearchSettings opt;
      opt.decimate = window_decimate(side, detector_.settings().quad_decimate, tracking_);
      search(kSearchWindow, w, opt);
      if (searches & kSearchWindow) window_d = opt.decimate;
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
    if ((tracked && !periodic_full) || seen) window();
    // A camera without its target whose image is still that of its last whole-image search
    // takes that search's result (TrackingSettings::change_pixels), up to the periodic search.
    const bool skip_whole = track && tracking_.enabled && !tracked &&
                            track->frames_since_full + 1 < tracking_.full_frame_every &&
                            unchanged(gray, track->whole_image);
    if (skip_whole) {
      searches |= kSkippedFullFrame;
      merge(kSkippedFullFrame, FrameDetections(track->whole_result));
      ++track->frames_since_full;
    } else if (!all_found(dets)) {
      search(kSearchFullFrame, whole, {});
      if (track) {
        track->frames_since_full = 0;
        const bool keep =
            !tracked && tracking_.enabled && tracking_.change_pixels > 0 && !all_found(dets);
        track->whole_image = keep ? this_reference() : ChangeReference{};
        track->whole_result = keep ? dets : FrameDetections{};
      }
    } else {
      ++track->frames_since_full;
    }
    if (tracked && periodic_full) window();
    // Acquisition: a blind camera's every acquire_every-th frame at full resolution (unless its
    // image is that of the last acquisition pass, which found nothing).
    if (track && tracking_.enabled && !tracked && tracking_.acquire_every > 0 &&
        track->blind_frames % tracking_.acquire_every == 0 &&
        detector_.settings().quad_decimate > 1.0 && !settled(dets)) {
      if (track->blind_frames - track->acquisition_at < tracking_.full_frame_every &&
          unchanged(gray, track->acquisition_image)) {
        searches |= kSkippedAcquisition;
      } else {
        SearchSettings opt;
        opt.decimate = 1.0;
        search(kSearchAcquisition, whole, opt);
        const bool keep = tracking_.change_pixels > 0 && !all_found(dets);
        track->acquisition_image = keep ? this_reference() : ChangeReference{};
        track->acquisition_at = track->blind_frames;
      }
    }
  }
  if (track) {
    track->searches = searches;
    track->found_by = found_by;
    track->window_decimate = window_d;
    track->last_all.clear();
    for (const auto& t : dets.tags)
      if (t.index >= 0) track->last_all.push_back(dets.all[static_cast<size_t>(t.index)].corners);
    // No tag accepted, but a tag of a target decoded and rejected by the frame check alone: the
    // tag is there, so the next frame's window is searched around it (TrackState::last_seen).
    track->last_seen.clear();
    if (track->last_all.empty())
      for (const auto& t : dets.tags)
        if (t.status == TargetStatus::border_mismatch)
          for (const auto& d : dets.all)
            if (d.id == t.id) track->last_seen.push_back(d.corners);
    if (!track->last_all.empty()) {
      track->blind_frames = 0;
      // As after a whole-image search: the periodic one is full_frame_every frames away.
      if (searches & kSkippedFullFrame) track->frames_since_full = 0;
      track->whole_image = {};  // tracking: the next whole-image search is a new one
      track->whole_result = FrameDetections{};
      track->acquisition_image = {};
    } else {
      ++track->blind_frames;
    }
  }
  std::vector<Observation> out(target_count());
  for (size_t j = 0; j < out.size(); ++j) {
    Observation& obs = out[j];
    const TargetDecision& target = dets.targets[j];
    obs.status = target.status;
    obs.reason = target.reason;
    for (size_t k = 0; k < target.tag_count; ++k) {
      const TagDecision& tag = dets.tags[target.first_tag + k];
      if (tag.index < 0) continue;
      const TagDetection& t = dets.all[static_cast<size_t>(tag.index)];
      if (!obs.delta) {
        obs.delta = true;
        obs.tag_id = t.id;
        obs.hamming = t.hamming;
        obs.margin = t.margin;
        obs.corners_px = t.corners;
      }
      obs.slots.push_back(static_cast<int>(k));
      obs.tag_corners_px.push_back(t.corners);
      obs.f_covariance.push_back(normalized_covariance(t, calib, detector_.settings()));
    }
    if (obs.delta) {
      obs.f_normalized.resize(static_cast<Eigen::Index>(8 * obs.slots.size()));
      for (size_t q = 0; q < obs.slots.size(); ++q)
        obs.f_normalized.segment<8>(static_cast<Eigen::Index>(8 * q)) =
            normalized_features(obs.tag_corners_px[q], calib);
    }
  }
  if (all) *all = std::move(dets);
  return out;
}

size_t FrontEnd::target_count() const {
  const auto& s = detector_.settings();
  return s.tags_per_target.empty() ? 1 : s.tags_per_target.size();
}

}  // namespace netvmo::frontend
