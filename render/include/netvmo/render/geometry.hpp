// Geometry for the renderer: rigid poses, the camera look-at pose, triangle meshes for boxes,
// planes and cylinders, and Wavefront OBJ parsing. The SO(3) / SE(3) maths (rotation vectors,
// exp and log) are observer/'s, the project's one Lie-group implementation, used here under
// render's names.
//
// Conventions (docs/extending.md, "Layout and conventions"): g_ab maps frame-b coordinates to frame
// a; rotations are rotation vectors (axis * angle); twists are ordered [v; w].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::render {

using Pose = obs::SE3;
using Vec2 = Eigen::Vector2d;
using Vec3 = obs::Vec3;
using Vec6 = obs::Vec6;
using Mat3 = obs::Mat3;

/// Rotation matrix of a rotation vector (axis * angle): exp_so3; rotation vector (angle in
/// [0, pi]) of a rotation matrix: log_so3; pose from a position and a rotation vector:
/// make_pose; exp and log of a twist [v; w]: exp_se3, log_se3.
using obs::exp_se3;
using obs::exp_so3;
using obs::log_se3;
using obs::log_so3;
using obs::make_pose;

/// Camera pose g_wi (camera: x right, y down, z forward) of a camera at `eye` looking at
/// `target` with `up` pointing up in the image. Throws std::invalid_argument if degenerate.
Pose look_at(const Vec3& eye, const Vec3& target, const Vec3& up);

/// An indexed triangle mesh (single precision, as Embree stores it).
struct Mesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// Axis-aligned box centred at the origin with full side lengths `size` (x, y, z).
Mesh make_box(const Vec3& size);
/// Rectangle in the z = 0 plane centred at the origin, sides sx (along x) and sy (along y),
/// front face +z (planes are rendered two-sided).
Mesh make_plane(double sx, double sy);
/// Closed cylinder of the given radius, axis z, from z = -height/2 to +height/2.
Mesh make_cylinder(double radius, double height, int segments = 32);
/// Parses Wavefront OBJ text (v and f records; polygons are fanned into triangles; negative
/// indices allowed; texture/normal indices ignored). `name` is used in error messages.
/// Throws std::invalid_argument with one line naming `name` and the line number.
Mesh parse_obj(const std::string& text, const std::string& name);
/// Applies a pose to every vertex.
Mesh transformed(const Mesh& mesh, const Pose& g);

}  // namespace netvmo::render
