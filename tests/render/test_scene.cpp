// Scene building blocks: shadows from directional and point lights, OBJ import, trajectories.
#include <gtest/gtest.h>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

double mean_over_tag(const cv::Mat& img, const FrameTruth& t) {
  // Mean of a small window around the projected tag centre's quiet zone corner region: use the
  // whole bounding box of the corners (tag + border), which is enough to compare lighting.
  double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
  for (const auto& c : t.corners) {
    u0 = std::min(u0, c->x());
    v0 = std::min(v0, c->y());
    u1 = std::max(u1, c->x());
    v1 = std::max(v1, c->y());
  }
  return cv::mean(img(cv::Rect(cv::Point(int(u0), int(v0)), cv::Point(int(u1), int(v1)))))[0];
}

Body blocker(const Vec3& centre) {
  Body b;
  Shape s;
  s.kind = Shape::Kind::Box;
  s.size = Vec3(0.6, 0.6, 0.02);
  s.pose = make_pose(centre, Vec3::Zero());
  b.shapes.push_back(s);
  return b;
}

// A box between the light and the tag (not between the camera and the tag) darkens the tag to
// ambient only, and does not count as occlusion.
TEST(Shading, OccluderCastsShadowOnTag) {
  for (auto kind : {Light::Kind::Directional, Light::Kind::Point}) {
    auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.5), Vec3::Zero()), 1);
    Light& l = s.lights[0];
    l.kind = kind;
    l.direction = Vec3(1, 0, 1);      // directional: travels +x, +z
    l.position = Vec3(-1.0, 0, 0.5);  // point: up-left of the tag, same side as the camera
    l.intensity = kind == Light::Kind::Point ? 0.7 * 1.25 : 0.7;
    Renderer lit(s);
    // Blocker on the light's path, 0.45 m in front of the tag and off to the -x side.
    s.occluders.push_back(
        blocker(kind == Light::Kind::Directional ? Vec3(-0.45, 0, 1.05) : Vec3(-0.5, 0, 1.0)));
    Renderer shadowed(s);
    const FrameTruth t = shadowed.truth(0, 0);
    EXPECT_DOUBLE_EQ(t.visible_fraction, 1.0);
    const double a = mean_over_tag(lit.render(0, 0), t),
                 b = mean_over_tag(shadowed.render(0, 0), t);
    EXPECT_LT(b, 0.6 * a) << "light kind " << int(kind) << ": lit " << a << " shadowed " << b;
    // Without shadow rays the blocker changes nothing on the tag.
    s.lights[0].shadows = false;
    Renderer no_shadow(s);
    EXPECT_NEAR(mean_over_tag(no_shadow.render(0, 0), t), a, 0.5);
  }
}

TEST(Mesh, ParseObjFansPolygonsAndNamesBadLines) {
  const Mesh m = parse_obj(
      "# quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "f 1/1/1 2/2/2 3/3/3 4/4/4\nf -1 -2 -3\n",
      "quad.obj");
  EXPECT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (std::array<std::uint32_t, 3>{3, 2, 1}));
  try {
    parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 7\n", "bad.obj");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj:3:"), std::string::npos) << e.what();
  }
}

TEST(Mesh, ObjTargetBodyRenders) {
  // An OBJ box behind the tag renders like the built-in box (same silhouette pixels).
  auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.5), Vec3(0.3, 0.4, 0)), 1);
  Shape box;
  box.kind = Shape::Kind::Box;
  box.size = Vec3(0.4, 0.4, 0.4);
  box.pose = make_pose(Vec3(0, 0, -0.201), Vec3::Zero());
  box.material.albedo = 0.3;
  s.target().shapes = {box};
  Renderer a(s);
  const Mesh bm = make_box(box.size);
  std::string obj;
  for (const auto& v : bm.vertices)
    obj += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
           std::to_string(v.z()) + "\n";
  for (const auto& t : bm.triangles)
    obj += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
           std::to_string(t[2] + 1) + "\n";
  s.target().shapes[0].kind = Shape::Kind::Mesh;
  s.target().shapes[0].mesh = parse_obj(obj, "box.obj");
  Renderer b(s);
  EXPECT_EQ(cv::countNonZero(a.render(0, 0) != b.render(0, 0)), 0);
}

TEST(Trajectory, KeyframesInterpolateOnSE3AndTwistIntegrates) {
  Trajectory k;
  k.kind = Trajectory::Kind::Keyframes;
  k.keyframes = {{0.0, make_pose(Vec3(0, 0, 0), Vec3(0, 0, 0))},
                 {2.0, make_pose(Vec3(2, 0, 0), Vec3(0, 0, 1.0))}};
  EXPECT_TRUE(k.at(-1).isApprox(k.keyframes[0].g));
  EXPECT_TRUE(k.at(5).isApprox(k.keyframes[1].g));
  const Pose mid = k.at(1.0);
  EXPECT_NEAR(log_so3(mid.linear()).z(), 0.5, 1e-12);  // half the rotation
  // Screw motion: the midpoint is off the straight line between the positions.
  EXPECT_GT(std::abs(mid.translation().y()), 1e-3);
  // Constant twist: pure translation integrates linearly, rotation about z by w t.
  Trajectory t;
  t.kind = Trajectory::Kind::Twist;
  t.g0 = make_pose(Vec3(1, 2, 3), Vec3(0, 0, 0));
  t.twist << 0.5, 0, 0, 0, 0, 0.2;
  EXPECT_NEAR(log_so3(t.at(2.0).linear()).z(), 0.4, 1e-12);
  t.twist << 0.5, 0, 0, 0, 0, 0;
  EXPECT_TRUE(t.at(2.0).translation().isApprox(Vec3(2, 2, 3)));
}

}  // namespace
}  // namespace netvmo::render
