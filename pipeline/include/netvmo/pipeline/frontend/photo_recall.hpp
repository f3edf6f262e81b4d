// The front end judged against libapriltag on real photos: every tag libapriltag itself decodes
// in a photo is a reference, and the front end should keep every fully visible one
// (docs/frontend.md, "Real photos"; `netvmo detect --photos`).
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// One tag as libapriltag decodes it with its own settings (the reference).
struct ReferenceTag {
  int id = -1;
  int hamming = 0;
  double margin = 0.0;
  std::array<cv::Point2d, 4> corners{};  ///< OpenCV pixels, libapriltag order
  double narrowest = 0.0;                ///< shortest side [px]
  /// The black square and a one-cell quiet zone around it lie inside the image.
  bool fully_visible = false;
};

/// The bits libapriltag corrects when it makes the reference (its default).
inline constexpr int kReferenceBitsCorrected = 2;

/// libapriltag's detections of `decoder`'s family in an 8-bit gray image, with libapriltag's
/// defaults but for a full-resolution quad search (quad_decimate 1, quad_sigma 0, refine_edges
/// on, decode_sharpening 0.25, min_white_black_diff 5, 1 thread); `decoder` corrects
/// kReferenceBitsCorrected bits (std::invalid_argument otherwise).
std::vector<ReferenceTag> reference_detections(const cv::Mat& gray, const TagDecoder& decoder);

/// How a reference tag fared in the front end.
struct PhotoTagResult {
  ReferenceTag ref;
  /// Counted in the recall: hamming 0, fully visible, narrowest side >= min_side_px, and its
  /// id decoded once in the photo (two tags of one id are duplicate_id by design).
  bool eligible = false;
  TargetStatus status = TargetStatus::not_found;
  std::string reason;                       ///< the front end's reason (empty when detected)
  double corner_difference = 0.0;           ///< largest corner distance to libapriltag's [px]
  std::array<cv::Point2d, 4> corners_px{};  ///< the front end's corners when detected
  /// The frame check on libapriltag's own quad after the front end's refinement (whatever the
  /// front end decided): where a loss comes from.
  BorderCheck check;
};

/// Settings of evaluate_photo().
struct PhotoRecallSettings {
  double min_side_px = 20.0;  ///< reference tags narrower than this are not counted
};

/// The front end (`settings` with the target ids replaced by the reference's, every id a
/// target of its own, decided in one pass from a camera with no history: the full-frame
/// search and the acquisition pass) on one photo, against libapriltag's detections of the same
/// family. `calib` undistorts the refinement and the check where the photo's camera is known.
/// `decoder`, of the settings' family with kReferenceBitsCorrected bits, is used for the
/// reference and, where the settings correct as many bits, for the front end (a folder of photos
/// builds libapriltag's decoding table once; see TagDecoder); nullptr: built for this photo.
std::vector<PhotoTagResult> evaluate_photo(const cv::Mat& gray, const io::Calibration& calib,
                                           const DetectorSettings& settings,
                                           const TrackingSettings& tracking,
                                           const PhotoRecallSettings& recall = {},
                                           std::shared_ptr<const TagDecoder> decoder = nullptr);

/// photos.csv's header (`netvmo detect --photos`; docs/frontend.md, "Real photos"), without its
/// newline: the reference tag, the front end's decision, the frame check on libapriltag's own
/// refined quad, libapriltag's corners and the front end's, and the photo's resampling.
extern const char* const kPhotosHeader;

/// photos.csv's row of reference tag `t` of the photo `file` (as the report names it), in which
/// measure_resampling() found `resampling`; without its newline, commas of reasons as ';'.
std::string format_photo_row(const std::string& file, const PhotoTagResult& t,
                             const Resampling& resampling);

/// A calibration for a photo whose camera is unknown: no distortion, f = the larger image side,
/// the principal point at the centre (only the front end's corners are used).
io::Calibration nominal_calibration(int width, int height);

/// Totals over photos: eligible reference tags kept, and every loss by status.
struct PhotoRecall {
  int photos = 0, references = 0, eligible = 0, kept = 0;
  std::map<TargetStatus, int> lost;        ///< eligible tags lost, by status
  std::vector<double> corner_differences;  ///< of the kept eligible tags [px]
  int resampled = 0;  ///< photos that look resampled by nearest neighbour (resampling.hpp)
  /// One photo's tags and what measure_resampling() found in it.
  void add(const std::vector<PhotoTagResult>& photo, const Resampling& resampling = {});
  double recall() const { return eligible ? static_cast<double>(kept) / eligible : 1.0; }
};

}  // namespace netvmo::frontend
