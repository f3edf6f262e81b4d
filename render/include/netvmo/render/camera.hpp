// Pinhole cameras with optional OpenCV radial-tangential distortion (k1, k2, p1, p2, k3).
// Pixel convention (OpenCV): pixel (col, row) has its centre at continuous (col, row) and
// covers [col-0.5, col+0.5] x [row-0.5, row+0.5].
#pragma once

#include <array>
#include <optional>

#include "netvmo/render/geometry.hpp"
#include "netvmo/render/trajectory.hpp"

namespace netvmo::render {

struct Intrinsics {
  int width = 640, height = 480;
  double fx = 600, fy = 600;
  double cx = 319.5, cy = 239.5;
  std::array<double, 5> dist{};  ///< k1, k2, p1, p2, k3 (OpenCV order); all zero = none

  bool has_distortion() const;
  /// Normalized undistorted point (x/z, y/z) -> distorted normalized point (OpenCV model).
  Vec2 distort(const Vec2& xn) const;
  /// Inverse of distort() by Newton iteration; nullopt if it does not converge.
  std::optional<Vec2> undistort(const Vec2& xd) const;
  /// Camera-frame point -> pixel with distortion (like cv::projectPoints); nullopt if z <= 0.
  std::optional<Vec2> project(const Vec3& p_cam) const;
  /// Pixel (u, v) -> undistorted normalized point.
  std::optional<Vec2> unproject(const Vec2& uv) const;
  /// Throws std::invalid_argument naming the problem (size, focal length, ...).
  void validate() const;
};

/// One camera of the network. id is the positive integer of the scenario.
///
/// A moving camera's true pose follows `motion`; its believed pose is the true one seen
/// through a mis-registered world frame, Delta(t) g_wi,true(t), with
///   Delta(0) = g_wi_believed g_wi,true(0)^-1   (the localisation error at t = 0) and
///   Delta(t) = [exp(t hat(drift_w)), t drift_v] Delta(0)   (a drift of the mis-registration),
/// so a static target's fictitious pose Delta(t) g_wo stays put while only the camera moves.
/// A static camera without drift believes g_wi_believed at every frame.
struct CameraSpec {
  int id = 1;
  Intrinsics intrinsics;
  Pose g_wi_true = Pose::Identity();      ///< true pose at t = 0 (motion->at(0) when moving)
  Pose g_wi_believed = Pose::Identity();  ///< believed pose at t = 0 (its localization error)
  std::optional<Trajectory> motion;       ///< true g_wi(t); none: static at g_wi_true
  Vec6 believed_drift = Vec6::Zero();     ///< [drift_v (m/s); drift_w (rad/s)], world frame
  /// Its own frame rate [1/s]; none: the scene's fps (SceneDescription::image_times).
  std::optional<double> fps;
  double start = 0.0;  ///< time of its first image [s] (>= 0)

  /// True pose at time t [s] (used to render and for the ground truth).
  Pose true_pose(double t) const { return motion ? motion->at(t) : g_wi_true; }
  /// Believed pose at time t [s].
  Pose believed_pose(double t) const;
  /// Whether the true or the believed pose changes over time.
  bool moving() const;
};

}  // namespace netvmo::render
