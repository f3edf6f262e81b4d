// Small scenes shared by the renderer tests.
#pragma once

#include "netvmo/render/renderer.hpp"

namespace netvmo::render::testing {

/// One camera at the world origin looking along +z (g_wi = I), a tag facing it at `g_wo`,
/// one directional light along the camera axis, no noise, no other geometry.
inline SceneDescription single_tag_scene(const Pose& g_wo, int spp = 16, double size = 0.2) {
  SceneDescription s;
  CameraSpec cam;
  cam.id = 1;
  cam.intrinsics.width = 640;
  cam.intrinsics.height = 480;
  cam.intrinsics.fx = 600;
  cam.intrinsics.fy = 600;
  cam.intrinsics.cx = 319.5;
  cam.intrinsics.cy = 239.5;
  s.cameras.push_back(cam);
  s.target().tag.size = size;
  s.target().motion = Trajectory::fixed(g_wo);
  Light l;
  l.direction = Vec3(0, 0, 1);
  l.intensity = 0.7;
  l.shadows = true;
  s.lights = {l};
  s.imaging.spp = spp;
  s.imaging.noise = false;
  s.imaging.background = 0.5;
  return s;
}

/// Tag pose in front of the camera at distance z, turned by rotation vector r; object z axis
/// roughly facing the camera (the camera looks along +z, so the tag's +z points back at it).
inline Pose facing_pose(const Vec3& p, const Vec3& r) {
  // Flip about x so the printed face (+z_o) looks at the camera, then apply r in the camera frame.
  return make_pose(p, Vec3::Zero()) * Pose(exp_so3(r)) * Pose(exp_so3(Vec3(M_PI, 0, 0)));
}

}  // namespace netvmo::render::testing
