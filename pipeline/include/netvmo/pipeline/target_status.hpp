// The front end's verdict on a target in one frame (TargetStatus), a stage-neutral header: the
// front end decides it (frontend/decision.hpp), the files that record it read and write it
// (io/truth_io.hpp, detections.csv).
#pragma once

#include <string>

namespace netvmo::frontend {

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

}  // namespace netvmo::frontend
