// Pose flips: a planar tag seen near head-on has two PnP solutions (mirror images about the
// line of sight) with nearly equal residuals, and a single camera's PnP can jump between them
// from one frame to the next. This is an evaluation metric of netvmo, not a quantity of the
// paper. A flip is a frame-to-frame orientation jump |log(R_{k-1}^T R_k)| above a threshold that
// must exceed the true rotation per frame plus the measurement noise (summary.json records the
// target's largest true rotation per frame next to the threshold, so a run can be checked).
#pragma once

#include <optional>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::run {

struct FlipSettings {
  /// Orientation jump between consecutive frames counted as a flip [deg]. Default 5: the
  /// scenarios' targets turn at most ~1-3 deg per frame (rocking_tag 0.67, moving_target
  /// measured in its summary), PnP noise near head-on is ~1 deg, and an IPPE flip at a view
  /// angle theta off the tag's normal turns the pose by ~2 theta.
  double threshold_deg = 5.0;
};

struct FlipCount {
  int flips = 0;  ///< consecutive pairs whose orientations differ by more than the threshold
  int pairs = 0;  ///< consecutive frames (k-1, k) that both have a pose
  double rate() const { return pairs ? static_cast<double>(flips) / pairs : 0.0; }
};

/// Counts flips in a sequence of poses, one per frame (nullopt: no pose in that frame; a pair
/// needs both of its frames).
FlipCount count_flips(const std::vector<std::optional<obs::SE3>>& poses, double threshold_deg);

/// The largest rotation [deg] between consecutive poses of a sequence (0 if no pair).
double max_step_deg(const std::vector<std::optional<obs::SE3>>& poses);

}  // namespace netvmo::run
