// What the detector finds in one frame: the decoded tags and the decision about each target.
// Corners in OpenCV pixels, libapriltag's order (tag_detector.hpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/target_status.hpp"

namespace netvmo::frontend {

/// Covariance of a quad's four corners [px^2], ordered (x0, y0, ..., x3, y3) as the corners.
using CornerCovariance = Eigen::Matrix<double, 8, 8>;

/// Length of the shortest side of a quad [px] (the "narrowest side" of a projected tag).
inline double narrowest_side(const std::array<cv::Point2d, 4>& corners) {
  double m = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < 4; ++k) m = std::min(m, cv::norm(corners[(k + 1) % 4] - corners[k]));
  return m;
}

/// One decoded tag.
struct TagDetection {
  int id = -1;
  int hamming = 0;
  double margin = 0.0;                   ///< libapriltag's decision margin
  std::array<cv::Point2d, 4> corners{};  ///< OpenCV pixels, libapriltag order
  cv::Point2d center;                    ///< OpenCV pixels
  /// The refined corners' covariance from the edge fits (refine_corners), set on an accepted
  /// detection whose corners came from them; nullopt otherwise.
  std::optional<CornerCovariance> corner_covariance;
};

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
