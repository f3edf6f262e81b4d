// AprilTag detection (libapriltag) with OpenCV corner refinement and the target decision.
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

#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// Sub-pixel corner refinement applied (in OpenCV) to the target's corners after detection.
enum class Refinement {
  none,           ///< libapriltag's corners as they are (its refine_edges already fits edges)
  corner_subpix,  ///< cv::cornerSubPix, window scaled to the tag's cell size
  edge_lines,     ///< lines fitted to sub-pixel samples of the four outer border edges,
                  ///< intersected (in undistorted coordinates when a calibration is given)
};
const char* to_string(Refinement r);
/// "none", "subpix", "edges"; throws InputError otherwise.
Refinement parse_refinement(const std::string& name);

/// Detector settings. Defaults documented next to each field.
struct DetectorSettings {
  // libapriltag (apriltag_detector_t) settings
  std::string family = "tag36h11";  ///< tag family (see render::tag_families())
  double quad_decimate = 2.0;       ///< decimation of the image for quad search (>= 1)
  double quad_sigma = 0.0;          ///< Gaussian blur sigma applied before quad search
  /// Worker threads of libapriltag. 1: the detection runs on the calling thread. libapriltag
  /// 3.3.0 (Debian 12) has a race in its worker pool: a worker woken spuriously may read a task
  /// from an array that workerpool_add_task is reallocating, and call through a stale pointer
  /// (AprilRobotics/apriltag pull request 339, merged after 3.3.0). Seen once here as a SEGV in
  /// a libapriltag thread under AddressSanitizer. netvmo runs cameras in parallel itself (one
  /// detector per worker, ImageRunOptions::workers), so 1 costs `netvmo run` nothing; > 1 only
  /// speeds up a single camera's detection, with that risk.
  int nthreads = 1;
  bool refine_edges = true;         ///< libapriltag's edge refinement of the quads
  double decode_sharpening = 0.25;  ///< sharpening of the decoded bit samples
  int bits_corrected = 2;           ///< error bits the decoder may correct (libapriltag default)
  /// libapriltag qtp.min_white_black_diff: local contrast (gray levels) below which a region is
  /// not thresholded. libapriltag's default is 5; 20 skips the quad fitting of sensor-noise
  /// clusters (about 5x faster on 640x480 frames with noise sigma 2, see the README's front-end
  /// benchmark) and still finds tags whose black/white contrast is 40 gray levels or more (tested).
  int min_white_black_diff = 20;
  // Acceptance of the target tag
  int target_id = 0;  ///< the target's (primary) tag id
  /// The ids of the body's other tags (a tag bundle: network.yaml's target.bundle, in its
  /// order), each decided by the same rules as target_id. Empty (default): a single tag.
  std::vector<int> bundle_ids;
  /// Several targets (network.yaml `targets:`), decided in the same pass: how many of the tags
  /// [target_id, bundle_ids...] belong to each target, in order (target j's tags follow target
  /// j - 1's; each target is decided as a body of its own). Empty (default): one target.
  std::vector<int> tags_per_target;
  double min_decision_margin = 20.0;  ///< reject target detections with a lower decision margin
  int max_hamming = 1;                ///< reject target detections with more corrected bits
  // Refinement of the accepted target's corners
  Refinement refinement = Refinement::edge_lines;
  // Border / quiet-zone consistency check of the accepted target's refined corners (see
  // check_border()): a quad with a side on an occluder's outline, a shadow edge or the image
  // border is rejected as TargetStatus::border_mismatch.
  bool border_check = true;
  /// A contrast sample passes when (quiet zone - border) >= this x (local white - border).
  /// 0.2 keeps a quiet zone in deep shadow next to a lit border (0.3 of the lit white, as the
  /// renderer's ambient-only shadows); an occluder close to the black ink fails it.
  double border_min_contrast = 0.2;
  /// A side fails when more than this fraction of its contrast samples fail.
  double border_max_failed_fraction = 0.2;
  /// A side fails when the inner edge of its black border (measured where the adjacent data
  /// cell is white) lies further than this from one cell inside the side [px]. Measured on
  /// rendered frames: at most 0.49 px on fully visible tags, at least 0.68 px on quads with
  /// a corner more than 1 px off (README, front end).
  double border_max_thickness_error = 0.6;
  /// Blur allowance of the thickness test [px of offset per px of measured blur]: when every
  /// measured side (at least 3, and every side with a white data cell next to it) looks thinner
  /// than a cell, the thinning of the least thin one is discounted from all sides, up to this x
  /// BorderCheck::edge_blur. 1.0 covers a gamma-encoded camera: encoding (v^(1/2.2)) an edge
  /// blurred by a Gaussian of sigma s moves it 0.42 s (black ink at 5 % of the white) to 0.47 s
  /// (3 %) toward the dark side, so a correct border looks 0.83-0.94 s thinner on all sides.
  /// 0: the fixed limit alone.
  double border_blur_allowance = 1.0;
};

/// One decoded tag.
struct TagDetection {
  int id = -1;
  int hamming = 0;
  double margin = 0.0;                   ///< libapriltag's decision margin
  std::array<cv::Point2d, 4> corners{};  ///< OpenCV pixels, libapriltag order
  cv::Point2d center;                    ///< OpenCV pixels
};

/// The front end's decision about the target in one frame. Every status but `detected` is a
/// reason for not using the frame. Decision: the detections of the target id with hamming <=
/// max_hamming and margin >= min_decision_margin are refined and border-checked; exactly one
/// passing is `detected`, whatever the others (a partly visible second tag of the same id, e.g.
/// on a neighbouring face of a cube, fails its check and does not hide the good one); two or
/// more passing is `duplicate_id`; none passing gives the reason of the best candidate.
enum class TargetStatus {
  detected,         ///< exactly one acceptable detection of the target id, corners checked
  not_found,        ///< the target id was not decoded
  duplicate_id,     ///< two or more detections of the target id pass every check: all rejected
  low_margin,       ///< decoded, but the decision margin is below min_decision_margin
  high_hamming,     ///< decoded, but with more corrected bits than max_hamming
  border_mismatch,  ///< the corners do not frame a black border inside a white quiet zone
  no_image,         ///< no image for this camera and frame (missing or unreadable: blind)
};
/// The status as one token, as in detections.csv's `status` column: detected, not_found,
/// duplicate_id, low_margin, high_hamming, border_mismatch, no_image.
const char* to_string(TargetStatus s);
/// Inverse of to_string(TargetStatus); throws InputError for anything else.
TargetStatus parse_target_status(const std::string& token);
/// Every status, in enum order.
inline constexpr TargetStatus kAllTargetStatuses[] = {
    TargetStatus::detected,   TargetStatus::not_found,    TargetStatus::duplicate_id,
    TargetStatus::low_margin, TargetStatus::high_hamming, TargetStatus::border_mismatch,
    TargetStatus::no_image};

/// The decision about one tag of the target's body (the rules of TargetStatus, per id).
struct TagDecision {
  int id = -1;
  TargetStatus status = TargetStatus::not_found;
  std::string reason;  ///< empty when detected
  int index = -1;      ///< index into FrameDetections::all of the accepted detection, or -1
};

/// The decision about one target (a body of one or more tags) in one frame.
struct TargetDecision {
  TargetStatus status = TargetStatus::not_found;
  std::string reason;    ///< empty when detected
  size_t first_tag = 0;  ///< its tags are FrameDetections::tags[first_tag, first_tag + tag_count)
  size_t tag_count = 1;
};

/// All tags decoded in a frame and the decision about the target. With a bundle
/// (DetectorSettings::bundle_ids) the target is `detected` when at least one of its tags is;
/// otherwise the status and reason are those of the tag that got furthest (duplicate_id, then
/// border_mismatch, low_margin, high_hamming; the primary first on ties), the reason prefixed by
/// `tag <id>: `, or `ids 0, 1 not decoded (...)` when none was decoded.
struct FrameDetections {
  std::vector<TagDetection> all;  ///< every decoded tag (other ids are reported, not used)
  TargetStatus status = TargetStatus::not_found;
  std::string reason;     ///< why the target was rejected (empty when detected)
  int target_index = -1;  ///< index into `all` of the accepted primary tag, or -1
  /// One decision per tag of the body: the primary, then the bundle in order (empty when the
  /// image was not searched). Several targets: every target's tags, target after target.
  std::vector<TagDecision> tags;
  /// One decision per target (DetectorSettings::tags_per_target; one entry for a single
  /// target), each by the rules above over its own tags; `status` and `reason` are target 0's.
  std::vector<TargetDecision> targets;
  /// The accepted target detection (refined corners), or nullptr.
  const TagDetection* target() const {
    return target_index >= 0 ? &all[static_cast<size_t>(target_index)] : nullptr;
  }
};

/// How one search is done (the front end's tracking window and acquisition pass use these).
struct SearchOptions {
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

/// libapriltag detector, created once and reused across frames (not thread-safe: one
/// detect() at a time; it uses `nthreads` workers internally).
class TagDetector {
 public:
  explicit TagDetector(DetectorSettings settings = {});
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
                         const io::Calibration* calib = nullptr, const SearchOptions& opt = {});

  const DetectorSettings& settings() const;
  /// Cells across the black border square (8 for tag36h11): corners are at this square.
  int border_cells() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Result of check_border().
struct BorderCheck {
  bool checked = false;  ///< false: not applicable (reversed-border family), `ok` stays true
  bool ok = true;        ///< the corners frame a black border inside a white quiet zone
  std::string reason;    ///< the worst failing side and why (empty when ok)
  /// Per side (side k runs from corner k to corner k+1): contrast samples, and how many failed.
  std::array<int, 4> samples{}, failed{};
  /// Per side: contrast samples outside the image (any one fails the side: a quiet zone cut by
  /// the image border cannot be verified).
  std::array<int, 4> outside{};
  /// Per side: the larger offset of the inner edge of the black border from one cell inside
  /// the side, at the ends of the measured stretch [px], negative when the border looks
  /// thinner than one cell; NaN where fewer than 4 points were measured (no white data cell
  /// next to that side, or the steps were not clean).
  std::array<double, 4> thickness_error{};
  /// The image is point-sampled (aliased) along the sides: no pixel straddling a side has an
  /// intermediate value. Edge positions are then quantised to the pixel grid by up to 0.5 px.
  bool aliased = false;
  /// The limit the thickness errors were held to: border_max_thickness_error, plus 0.5 px
  /// when `aliased` (the border's two edges may then disagree by up to 1 px on a correct quad).
  double thickness_limit = 0.0;
  /// Gaussian sigma of the blur of the border's inner edges beyond the pixel's own [px]:
  /// sqrt(spread^2 - 0.25) of the median spread of the intensity differences across the
  /// measured inner-edge points (window +-0.5 cell; 0.25 px^2 is the spread of a sharp edge
  /// integrated over the pixel and interpolated bilinearly). The window truncates the spread,
  /// so heavy blur on small cells is underestimated (a smaller allowance). 0 when unmeasured.
  double edge_blur = 0.0;
  /// The offset discounted from every side's thickness error (<= 0): when all measured sides
  /// (at least 3, and every side with a white data cell next to it) look thinner, the error of
  /// the least thin one, but no lower than -border_blur_allowance x edge_blur; otherwise 0.
  double common_offset = 0.0;
};

/// The tag's bitmap as libapriltag prints it (apriltag_to_image): total_width x total_width
/// cells, 255 white / 0 black, row 0 at the top (+y) of the printed tag. Empty for an id
/// outside the family.
cv::Mat tag_pattern(const std::string& family, int id);

/// Border / quiet-zone consistency of the refined corners of a decoded tag whose bitmap is
/// `pattern` (tag_pattern()). The homography of the corners maps the object square (in bit
/// cells, the black square is [0, n]^2) to the image, in undistorted pixels when `calib` has
/// distortion (sample points are re-distorted). Along each side (side k runs from corner k to
/// corner k+1):
///  - contrast, every quarter cell: a quiet-zone sample half a cell outside the side and a
///    border sample half a cell inside (the centres of the white ring and of the black border
///    cell row). It passes when quiet - border >= border_min_contrast x (white - border), with
///    `white` the median of the tag's white data cells within 2.5 cells of the border sample:
///    a local level, so a shadow that darkens both sides of the edge scales both sides of the
///    inequality. The side fails when more than border_max_failed_fraction of its 4n samples
///    fail (an occluder darker than the quiet zone beyond the side, or corners more than half a
///    cell off), or when any sample lies outside the image (a quiet zone cut by the image
///    border cannot be verified; a partly visible tag must not pass, see TargetStatus).
///  - border thickness, where the data cell next to the border is white: the inner edge of the
///    border (the dark-to-bright step one cell inside the side) is located to sub-pixel at 5
///    points per such cell, by the centroid of the intensity differences along the normal as in
///    the edge refinement (window 0.45 cell, at most 4 px), kept only where the centroid in
///    half that window agrees to 0.2 px (no second edge, such as a shadow boundary, nearby).
///    A line through the offsets (robust least squares along the side) is evaluated at the
///    first and last measured point: the side's thickness error e_k (the one of larger
///    magnitude). A camera's tone curve moves every edge of a blurred print toward the dark
///    side, so a correct border looks thinner on all four sides: when at least 3 sides are
///    measured, every side with a white data cell next to it among them (a side whose inner edge
///    is not found is no evidence), and all are thinner (e_k < 0), the common offset c is the
///    error of the least thin one, but no lower than -border_blur_allowance x `edge_blur` (the
///    measured Gaussian blur of the inner edges beyond the pixel's own); otherwise c = 0 (a
///    border thicker on every side is not discounted). The side fails when
///    |e_k - c| > border_max_thickness_error (needs 4 points), 0.5 px more in a point-sampled
///    image (`aliased`). A side fitted to an occluder's outline that hides part of the border cell
///    row makes the border look thinner towards the wrong corner, whatever the occluder's
///    brightness; the other sides do not share that error, so c stays near 0.
/// Families without a black border ring inside a white one (tagStandard41h12, ...) are not
/// checked (`checked` false).
BorderCheck check_border(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners,
                         const cv::Mat& pattern, int border_cells, const DetectorSettings& s,
                         const io::Calibration* calib = nullptr);

/// Refines the four corners of one detected quad in place (OpenCV). `border_cells` is the
/// number of bit cells across the black border square. Exposed for tests and benchmarks.
void refine_corners(const cv::Mat& gray, std::array<cv::Point2d, 4>& corners, Refinement mode,
                    int border_cells, const io::Calibration* calib = nullptr);

}  // namespace netvmo::frontend
