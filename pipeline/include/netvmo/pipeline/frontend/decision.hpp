// The target decision: from the decoded tags of a frame and a check of each candidate's corners
// to one TagDecision per tag of a body and one TargetDecision per target (detections.hpp).
#pragma once

#include <array>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/detections.hpp"
#include "netvmo/pipeline/frontend/detector_settings.hpp"

namespace netvmo::frontend {

/// A candidate's corners after the refinement and the frame check: `ok` false with the reason.
struct CandidateCheck {
  bool ok = true;
  std::string reason;
  /// The refined corners' covariance (refine_corners), when the refinement gives one.
  std::optional<CornerCovariance> corner_covariance;
};
/// Refines a candidate's corners in place and checks them.
using CandidateChecker = std::function<CandidateCheck(std::array<cv::Point2d, 4>& corners)>;

/// The decision about tag `tag_id`. Every detection of the id in `all` that passes hamming
/// (<= max_hamming) and margin (>= min_decision_margin) is refined and checked by `check`; the
/// duplicate-id rule counts only those that pass, so a partly visible second tag of the same id
/// (a neighbouring face of a cube, a tag cut by the image border) does not hide a good one. The
/// passing candidate's corners in `all` are replaced by its refined ones. Without a passing one,
/// the reason is the furthest any candidate got: the check, then margin, then hamming.
TagDecision decide_tag(int tag_id, std::vector<TagDetection>& all, const DetectorSettings& s,
                       const CandidateChecker& check);

/// The tags of each target (DetectorSettings::tags_per_target, or all of them as one), each
/// not found.
std::vector<TargetDecision> target_ranges(const DetectorSettings& s);

/// Each target's status and reason from its tags' decisions (out.tags): a single tag's own; a
/// bundle is `detected` when at least one of its tags is, else the status and reason of the tag
/// that got furthest (duplicate_id, then border_mismatch, low_margin, high_hamming; the primary
/// first on ties), prefixed by `tag <id>: `, or `ids 0, 1 not decoded (...)` when none was
/// decoded. Sets out.targets, and out.status / out.reason to target 0's.
void decide_targets(FrameDetections& out, const DetectorSettings& s);

/// A region that was not searched: every target not found (their tags' ids in the reason).
FrameDetections not_searched(FrameDetections out, const DetectorSettings& s);

}  // namespace netvmo::frontend
