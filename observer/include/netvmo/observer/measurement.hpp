// What one camera knows about the target in one frame: the input of the visual feedback term
// delta_i(t) k_e e_ei of (eq:input_f-).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::obs {

/// One camera's measurement, held from one frame to the next (zero-order hold).
struct Measurement {
  /// delta_i(t) of (eq:input_f-): camera i sees the target (on images: its front end decoded the
  /// target's tag in this frame; never ground truth).
  bool delta = false;
  /// Image features f_i of (eq:visual_mea), 2m values: undistorted normalized image coordinates
  /// of the target's feature points in FeatureModel order (empty when unknown).
  Eigen::VectorXd f;
  /// The object points p_ol that go with f in this frame, when they differ from the error
  /// model's fixed FeatureModel (a tag bundle of which only some tags are seen: the corners of
  /// the seen tags, 4 per tag, f of size 2 x points_o.size()). Empty: the fixed model's points.
  std::vector<Vec3> points_o;
  /// The camera's own measured relative pose g_io (per-camera PnP on images), when it has one.
  std::optional<SE3> g_io_pnp;
  /// The true (fictitious) relative pose g_io_i (simulation, rendered data), when known.
  std::optional<SE3> g_io_true;
};

}  // namespace netvmo::obs
