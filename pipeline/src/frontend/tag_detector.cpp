#include "netvmo/pipeline/frontend/tag_detector.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/decision.hpp"
#include "netvmo/pipeline/stopwatch.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::frontend {

namespace {

/// libapriltag reports pixel centres at +0.5 (measured, see tests/pipeline/test_detector.cpp).
constexpr double kApriltagPixelOffset = 0.5;

/// A target found on a normalised copy (SearchSettings::normalized) is rejected when its corners
/// refined on the image and on the copy differ by more than this [px] (a shadow boundary along
/// a border edge; measured on moving_target: 0.01-0.21 px where the corners are right, 0.53 px
/// where the image fit put a corner 1.4 px off).
constexpr double kMaxNormalizedDisagreement = 0.35;

}  // namespace

TagDecoder::TagDecoder(const std::string& family, int bits_corrected)
    : name_(family), bits_(bits_corrected), family_(render::create_tag_family(family)) {
  if (bits_corrected < 0 || bits_corrected > 3)
    throw std::invalid_argument("TagDecoder: bits_corrected must be in 0..3, not " +
                                std::to_string(bits_corrected));
  owner_ = apriltag_detector_create();
  if (!owner_) throw std::runtime_error("libapriltag: cannot create the detector");
  // The table is built into the family (family->impl) here, and freed with owner_.
  apriltag_detector_add_family_bits(owner_, family_.get(), bits_corrected);
  if (!family_->impl) {
    apriltag_detector_destroy(owner_);
    throw std::runtime_error("libapriltag: cannot build the decoding table of " + family + " for " +
                             std::to_string(bits_corrected) + " corrected bits (out of memory)");
  }
}

std::shared_ptr<const TagDecoder> TagDecoder::shared_or_new(
    std::shared_ptr<const TagDecoder> shared, const std::string& family, int bits_corrected) {
  if (shared && shared->decodes(family, bits_corrected)) return shared;
  return std::make_shared<const TagDecoder>(family, bits_corrected);
}

TagDecoder::~TagDecoder() {
  apriltag_detector_destroy(owner_);  // frees the table, before the family
}

void ApriltagDetectorDeleter::operator()(apriltag_detector* td) const {
  // Its family list emptied first: libapriltag's destroy would free the family's table, which
  // is the decoder's (TagDecoder).
  zarray_clear(td->tag_families);
  apriltag_detector_destroy(td);
}

ApriltagDetectorPtr create_apriltag_detector(const TagDecoder& decoder, const DetectorSettings& s) {
  if (s.bits_corrected != decoder.bits_corrected())
    throw std::invalid_argument(
        "create_apriltag_detector: bits_corrected " + std::to_string(s.bits_corrected) +
        ", but the decoder's table is for " + std::to_string(decoder.bits_corrected()));
  ApriltagDetectorPtr td(apriltag_detector_create());
  if (!td) throw std::runtime_error("libapriltag: cannot create the detector");
  // The family's table exists (TagDecoder): libapriltag adds the family and builds nothing.
  apriltag_detector_add_family_bits(td.get(), decoder.family(), s.bits_corrected);
  td->quad_decimate = static_cast<float>(s.quad_decimate);
  td->quad_sigma = static_cast<float>(s.quad_sigma);
  td->nthreads = s.nthreads;
  td->refine_edges = s.refine_edges;
  td->decode_sharpening = s.decode_sharpening;
  td->qtp.min_white_black_diff = s.min_white_black_diff;
  td->debug = false;
  return td;
}

TagDetection to_tag_detection(const apriltag_detection& det, cv::Point origin) {
  TagDetection d;
  d.id = det.id;
  d.hamming = det.hamming;
  d.margin = det.decision_margin;
  for (int k = 0; k < 4; ++k)
    d.corners[static_cast<size_t>(k)] = cv::Point2d(det.p[k][0] - kApriltagPixelOffset + origin.x,
                                                    det.p[k][1] - kApriltagPixelOffset + origin.y);
  d.center = cv::Point2d(det.c[0] - kApriltagPixelOffset + origin.x,
                         det.c[1] - kApriltagPixelOffset + origin.y);
  return d;
}

struct TagDetector::Impl {
  DetectorSettings s;
  std::shared_ptr<const TagDecoder> decoder;
  ApriltagDetectorPtr td;         // (destroyed before the decoder it uses)
  cv::Mat gray;                   // conversion buffer for non-gray input
  cv::Mat normalized;             // the image with the searched region normalised (SearchSettings)
  std::vector<cv::Mat> patterns;  // bitmap of each tag of the body, for the border check
  StageSeconds seconds;           // time spent, by stage

  Impl(DetectorSettings settings, std::shared_ptr<const TagDecoder> shared)
      : s(std::move(settings)) {
    validate(s);
    decoder = TagDecoder::shared_or_new(std::move(shared), s.family, s.bits_corrected);
    td = create_apriltag_detector(*decoder, s);
    patterns.push_back(tag_pattern(s.family, s.target_id));
    for (int id : s.bundle_ids) patterns.push_back(tag_pattern(s.family, id));
  }
};

TagDetector::TagDetector(DetectorSettings settings, std::shared_ptr<const TagDecoder> decoder)
    : impl_(std::make_unique<Impl>(std::move(settings), std::move(decoder))) {}
TagDetector::~TagDetector() = default;
TagDetector::TagDetector(TagDetector&&) noexcept = default;
TagDetector& TagDetector::operator=(TagDetector&&) noexcept = default;

const DetectorSettings& TagDetector::settings() const {
  return impl_->s;
}
const StageSeconds& TagDetector::seconds() const {
  return impl_->seconds;
}
const std::shared_ptr<const TagDecoder>& TagDetector::decoder() const {
  return impl_->decoder;
}

int TagDetector::border_cells() const {
  return impl_->decoder->family()->width_at_border;
}

FrameDetections TagDetector::detect(const cv::Mat& image, const io::Calibration* calib) {
  return detect(image, cv::Rect(0, 0, image.cols, image.rows), calib);
}

cv::Mat normalize_illumination(const cv::Mat& gray, int window) {
  CV_Assert(gray.type() == CV_8UC1 && window >= 1);
  const cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(window, window));
  cv::Mat white;
  cv::morphologyEx(gray, white, cv::MORPH_CLOSE, k, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  const int smooth = std::max(1, window / 4);
  cv::blur(white, white, cv::Size(smooth, smooth), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  cv::Mat white_f, gray_f, out;
  white.convertTo(white_f, CV_32F);
  cv::max(white_f, 8.0, white_f);  // no division by (near) zero in black areas
  gray.convertTo(gray_f, CV_32F);
  cv::divide(gray_f, white_f, gray_f, 240.0);
  gray_f.convertTo(out, CV_8U);  // saturates
  return out;
}

FrameDetections TagDetector::detect(const cv::Mat& image, const cv::Rect& region,
                                    const io::Calibration* calib, const SearchSettings& opt) {
  const cv::Mat* g = &image;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, impl_->gray, cv::COLOR_BGR2GRAY);
    g = &impl_->gray;
  } else if (image.type() != CV_8UC1) {
    throw std::invalid_argument("TagDetector::detect: expected an 8-bit gray or BGR image");
  }
  const DetectorSettings& s = impl_->s;
  FrameDetections out;
  char buf[200];
  std::snprintf(buf, sizeof buf, "id %d not decoded", s.target_id);
  out.reason = buf;
  if (g->empty()) return not_searched(std::move(out), s);
  if (!(opt.decimate == 0.0 || opt.decimate >= 1.0))
    throw std::invalid_argument("TagDetector::detect: decimate must be 0 or >= 1");
  if (opt.normalized && opt.normalize_window < 1)
    throw std::invalid_argument("TagDetector::detect: normalize_window must be >= 1");
  const double decimate = opt.decimate > 0.0 ? opt.decimate : s.quad_decimate;
  // Align the region to the decimation grid so a windowed search samples the same pixels as a
  // full-frame one (identical quads, identical corners).
  // libapriltag thresholds in 4x4 tiles of the decimated image: align to 4 x decimate.
  const int step = 4 * std::max(1, static_cast<int>(std::ceil(decimate)));
  cv::Rect aligned = region;
  aligned.x -= ((aligned.x % step) + step) % step;
  aligned.y -= ((aligned.y % step) + step) % step;
  aligned.width += region.x - aligned.x;
  aligned.height += region.y - aligned.y;
  const cv::Rect roi = aligned & cv::Rect(0, 0, g->cols, g->rows);
  // Nothing decodable in a tiny region; libapriltag needs a few tiles.
  if (roi.width < 16 || roi.height < 16) return not_searched(std::move(out), s);
  // libapriltag searches the region only (a view into the image, no copy, or its normalised
  // normalised copy); corners are mapped back to the whole image and refined there.
  const cv::Mat sub =
      opt.normalized ? normalize_illumination((*g)(roi), opt.normalize_window) : (*g)(roi);
  const cv::Mat* original = g;
  if (opt.normalized) {
    // Refinement and border check on the normalised region too: a shadow edge along a border
    // edge biases the edge fit on the image itself.
    g->copyTo(impl_->normalized);
    sub.copyTo(impl_->normalized(roi));
    g = &impl_->normalized;
  }
  image_u8_t im{sub.cols, sub.rows, static_cast<int32_t>(sub.step[0]),
                const_cast<uint8_t*>(sub.ptr<uint8_t>())};
  impl_->td->quad_decimate = static_cast<float>(decimate);
  const auto t_search = Clock::now();
  zarray_t* dets = apriltag_detector_detect(impl_->td.get(), &im);
  impl_->seconds.search += seconds_since(t_search);
  impl_->td->quad_decimate = static_cast<float>(s.quad_decimate);
  if (!dets) throw std::runtime_error("libapriltag: detection failed");
  for (int i = 0; i < zarray_size(dets); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(dets, i, &det);
    out.all.push_back(to_tag_detection(*det, roi.tl()));
  }
  apriltag_detections_destroy(dets);

  // Target decision, per tag of the body (decide_tag): each candidate refined and checked.
  const auto check_on = [&](const cv::Mat& pattern) -> CandidateChecker {
    return [&, pattern](std::array<cv::Point2d, 4>& corners) {
      const std::array<cv::Point2d, 4> found = corners;
      const auto t_refine = Clock::now();
      EdgeSamples edges;
      auto covariance = refine_corners(*g, corners, s.refinement, border_cells(), calib, &edges);
      const auto t_check = Clock::now();
      impl_->seconds.refinement += seconds_since(t_refine, t_check);
      BorderCheck bc = s.border_check
                           ? check_border(*g, corners, pattern, border_cells(), s, calib, &edges)
                           : BorderCheck{};
      const std::array<cv::Point2d, 4> fitted = corners;
      // Sides off their border's inner edge alone: kept halfway between the two explanations,
      // where the check passes on the inner edge (DetectorSettings::border_realign_max).
      if (!bc.ok)
        if (auto r = realign_and_check(*g, corners, bc, pattern, border_cells(), s, calib)) {
          if (covariance) *covariance += r->covariance;
          corners = r->corners;
          bc = std::move(r->check);
        }
      if (bc.ok && opt.normalized) {
        // Corners must not depend on the illumination correction: where a shadow boundary runs
        // along a border edge, the fits on the image and on its normalised copy disagree.
        std::array<cv::Point2d, 4> plain = found;
        refine_corners(*original, plain, s.refinement, border_cells(), calib);
        double moved = 0.0;
        for (size_t k = 0; k < 4; ++k) moved = std::max(moved, cv::norm(plain[k] - fitted[k]));
        if (moved > kMaxNormalizedDisagreement) {
          bc.ok = false;
          std::snprintf(buf, sizeof buf,
                        "shadow edge along the border: corners fitted on the image and on its "
                        "normalised copy differ by %.2f px",
                        moved);
          bc.reason = buf;
        }
      }
      // The corners of the print's cell grid, not of its inked outline (DetectorSettings::
      // correct_edge_bias).
      if (bc.ok && s.correct_edge_bias) {
        if (covariance) *covariance += edge_bias_covariance(corners, bc, calib);
        corners = remove_edge_bias(corners, bc, calib);
      }
      // Where the sides bow (a bent print), the corners where the bowed edges end
      // (DetectorSettings::border_bow_correction).
      if (bc.ok && bc.bow_taken_off) {
        if (covariance) *covariance += bow_covariance(bc.bow);
        corners = take_off_bow(corners, bc.bow, calib);
      }
      impl_->seconds.check += seconds_since(t_check);
      return CandidateCheck{bc.ok, bc.reason, std::move(covariance)};
    };
  };
  out.tags.push_back(decide_tag(s.target_id, out.all, s, check_on(impl_->patterns[0])));
  for (size_t k = 0; k < s.bundle_ids.size(); ++k)
    out.tags.push_back(decide_tag(s.bundle_ids[k], out.all, s, check_on(impl_->patterns[k + 1])));
  out.target_index = out.tags[0].index;
  decide_targets(out, s);
  return out;
}

}  // namespace netvmo::frontend
