// Pinhole cameras with optional OpenCV radial-tangential distortion (k1, k2, p1, p2, k3).
// Pixel convention (OpenCV): pixel (col, row) has its centre at continuous (col, row) and
// covers [col-0.5, col+0.5] x [row-0.5, row+0.5].
#pragma once

#include <array>
#include <optional>

#include "netvmo/render/geometry.hpp"

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
struct CameraSpec {
  int id = 1;
  Intrinsics intrinsics;
  Pose g_wi_true = Pose::Identity();      ///< used to render
  Pose g_wi_believed = Pose::Identity();  ///< what the camera believes (its localization error)
};

}  // namespace netvmo::render
