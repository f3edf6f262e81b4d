// What the detector finds in one frame: the decoded tags and the decision about each target.
// Corners in OpenCV pixels, libapriltag's order (tag_detector.hpp).
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace netvmo::frontend {

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

}  // namespace netvmo::frontend
