// AprilTag detection: libapriltag's search, then per candidate of a target tag the corner
// refinement (refine.hpp), the frame check (border_check.hpp) and the target decision
// (decision.hpp), giving FrameDetections (detections.hpp).
//
// Pixel convention: all corners are in OpenCV pixel coordinates (pixel (col,row) centred at
// continuous (col,row)). libapriltag 3.3 reports corners with pixel centres at +0.5, i.e.
//   u_opencv = u_apriltag - 0.5,  v_opencv = v_apriltag - 0.5
// (measured on synthesized images with exactly known corners, see tests/pipeline).
//
// Corner order: libapriltag's, unchanged. For a tag of side s in the object frame (x right of
// the printed tag, y up, z out of the printed face) corner k is the image of
//   c0 = (-s/2,-s/2,0), c1 = (s/2,-s/2,0), c2 = (s/2,s/2,0), c3 = (-s/2,s/2,0)
// i.e. obs::FeatureModel::square(s).points_o[k] (verified index by index in the tests).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "netvmo/pipeline/frontend/border_check.hpp"
#include "netvmo/pipeline/frontend/detections.hpp"
#include "netvmo/pipeline/frontend/detector_settings.hpp"
#include "netvmo/pipeline/frontend/refine.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/render/tag_family.hpp"

// libapriltag's types (apriltag/apriltag.h), for the set-up and conversion below.
struct apriltag_detector;
struct apriltag_family;
struct apriltag_detection;

namespace netvmo::frontend {

/// A tag family with libapriltag's decoding table for `bits_corrected` error bits (its "quick
/// decode" hash table of every code word within that many bits of a tag's: for tag36h11 and 2
/// bits 2.3 million slots, 36 MB, built in about 0.1 s; 2026-12-06, 2-core AMD EPYC VM).
/// libapriltag builds the table into the family when a detector is given it, and only reads it
/// while decoding (its own threads decode from one table in parallel), so every detector made
/// from one TagDecoder, on any thread, shares the one table. libapriltag's header asks for one
/// family instance per detector because its destroy frees the family's table: the detectors
/// made here take the family out of their list first (ApriltagDetectorDeleter), and must
/// correct the decoder's bits. Throws std::invalid_argument for an unknown family or bits outside
/// 0-3, std::runtime_error when libapriltag cannot build the table.
class TagDecoder {
 public:
  TagDecoder(const std::string& family, int bits_corrected);
  ~TagDecoder();
  TagDecoder(const TagDecoder&) = delete;
  TagDecoder& operator=(const TagDecoder&) = delete;

  const std::string& family_name() const { return name_; }
  int bits_corrected() const { return bits_; }
  /// Whether it decodes `family` correcting `bits_corrected` bits (a detector of those settings
  /// may share it).
  bool decodes(const std::string& family, int bits_corrected) const {
    return family == name_ && bits_corrected == bits_;
  }
  /// `shared` where it is given and decodes `family` correcting `bits_corrected` bits, else a
  /// new decoder of those.
  static std::shared_ptr<const TagDecoder> shared_or_new(std::shared_ptr<const TagDecoder> shared,
                                                         const std::string& family,
                                                         int bits_corrected);
  apriltag_family* family() const { return family_.get(); }

 private:
  std::string name_;
  int bits_;
  render::TagFamilyPtr family_;
  apriltag_detector* owner_ = nullptr;  ///< the detector whose destruction frees the table
};

/// A libapriltag detector of create_apriltag_detector(): destroying it leaves the decoder's
/// table to the decoder, which must outlive it.
struct ApriltagDetectorDeleter {
  void operator()(apriltag_detector* td) const;
};
using ApriltagDetectorPtr = std::unique_ptr<apriltag_detector, ApriltagDetectorDeleter>;

/// A libapriltag detector searching `decoder`'s family with its table and the libapriltag
/// settings of `s` (quad_decimate, quad_sigma, nthreads, refine_edges, decode_sharpening,
/// min_white_black_diff; no debug output); `s.bits_corrected` must be the decoder's
/// (std::invalid_argument otherwise). Throws std::runtime_error when libapriltag cannot create
/// it.
ApriltagDetectorPtr create_apriltag_detector(const TagDecoder& decoder, const DetectorSettings& s);

/// One libapriltag detection in OpenCV pixels (pixel convention above), found in an image
/// region whose top-left pixel is `origin` of the whole image.
TagDetection to_tag_detection(const apriltag_detection& det, cv::Point origin = {});

/// How one search is done (the front end's tracking window and acquisition pass use these).
struct SearchSettings {
  /// libapriltag quad_decimate for this search; 0: the settings' quad_decimate. 1 finds tags
  /// down to ~15 px that decimate 2 misses, at about twice the cost per searched pixel.
  double decimate = 0.0;
  /// Search a locally normalised copy of the region (normalize_illumination(), white level
  /// over `normalize_window` px) instead of the image itself, and refine and border-check the
  /// corners on it too. For tags crossed by a hard shadow edge.
  bool normalized = false;
  int normalize_window = 0;  ///< > 0 when `normalized`
};

/// The image divided by an estimate of its local white level: a morphological closing (max then
/// min filter) over a `window` x `window` square, which fills dark print narrower than the
/// window and keeps large-scale steps such as a shadow boundary, smoothed by a box filter of
/// a quarter of the window. A tag under a hard shadow edge becomes one tag of uniform contrast:
/// ink / paper on both sides of the edge. `window` should exceed the widest dark run of the tag
/// (5 bit cells is used). 8-bit in, 8-bit out (white ~ 240).
cv::Mat normalize_illumination(const cv::Mat& gray, int window);

/// Where a TagDetector's time went, summed over its detect() calls [s, wall time of the calling
/// thread]: libapriltag's search (quads and decoding, its own threads included), the corner
/// refinement and the border check (with the edge-bias correction).
struct StageSeconds {
  double search = 0.0, refinement = 0.0, check = 0.0;
  StageSeconds& operator+=(const StageSeconds& o) {
    search += o.search;
    refinement += o.refinement;
    check += o.check;
    return *this;
  }
};

/// libapriltag detector, created once and reused across frames (not thread-safe: one
/// detect() at a time; it uses `nthreads` workers internally).
class TagDetector {
 public:
  /// A detector for `settings`, on `decoder` where it is given and decodes the settings' family
  /// with their bits_corrected (detectors of one decoder share its table, see TagDecoder), else
  /// on a decoder of its own.
  explicit TagDetector(DetectorSettings settings = {},
                       std::shared_ptr<const TagDecoder> decoder = nullptr);
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;
  TagDetector(TagDetector&&) noexcept;
  TagDetector& operator=(TagDetector&&) noexcept;

  /// Detects all tags in an 8-bit gray (or BGR, converted) image, decides about the target and
  /// refines the accepted target's corners. `calib` (optional) lets the edge-line refinement
  /// fit straight lines in undistorted coordinates.
  FrameDetections detect(const cv::Mat& image, const io::Calibration* calib = nullptr);
  /// The same, searching only `region` of the image (tags must lie wholly inside it); corners
  /// are reported and refined in whole-image pixels.
  FrameDetections detect(const cv::Mat& image, const cv::Rect& region,
                         const io::Calibration* calib = nullptr, const SearchSettings& opt = {});

  const DetectorSettings& settings() const;
  /// Cells across the black border square (8 for tag36h11): corners are at this square.
  int border_cells() const;
  /// Time spent so far, by stage.
  const StageSeconds& seconds() const;
  /// The decoder it searches with, to share with other detectors of the same settings.
  const std::shared_ptr<const TagDecoder>& decoder() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace netvmo::frontend
