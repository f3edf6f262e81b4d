// Geometry for the renderer: rigid poses, small SE(3) helpers (render/ must not depend on
// observer/), triangle meshes for boxes, planes and cylinders, and Wavefront OBJ parsing.
//
// Conventions (../../../../../shared/DESIGN.md): g_ab maps frame-b coordinates to frame a;
// rotations are rotation vectors (axis * angle); twists are ordered [v; w].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace netvmo::render {

using Pose = Eigen::Isometry3d;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;

/// Rotation matrix of a rotation vector (axis * angle).
Mat3 rotation_from_vector(const Vec3& r);
/// Rotation vector (angle in [0, pi]) of a rotation matrix.
Vec3 rotation_to_vector(const Mat3& R);
/// Pose from a position and a rotation vector.
Pose make_pose(const Vec3& p, const Vec3& r);
/// exp of the twist [v; w] (closed form).
Pose exp_se3(const Vec6& V);
/// log of a pose as a twist [v; w], rotation angle in [0, pi].
Vec6 log_se3(const Pose& g);
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
