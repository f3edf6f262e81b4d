// Visibility ground truth: outside the field of view, behind the camera, fully occluded and half
// occluded give visible fraction 0, 0, 0 and about 0.5; an unobstructed tag gives 1.
#include <gtest/gtest.h>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

Body wall(const Vec3& centre, const Vec3& size) {
  Body b;
  b.name = "wall";
  Shape s;
  s.kind = Shape::Kind::Box;
  s.size = size;
  s.pose = make_pose(centre, Vec3::Zero());
  b.shapes.push_back(s);
  return b;
}

TEST(Visibility, UnobstructedTagIsFullyVisible) {
  Renderer r(testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.2), Vec3(0.2, 0.1, 0))));
  const FrameTruth t = r.truth(0, 0);
  EXPECT_TRUE(t.in_fov);
  EXPECT_DOUBLE_EQ(t.visible_fraction, 1.0);
}

TEST(Visibility, OutsideFieldOfView) {
  Renderer r(testing::single_tag_scene(testing::facing_pose(Vec3(2.5, 0, 1.2), Vec3::Zero())));
  const FrameTruth t = r.truth(0, 0);
  EXPECT_FALSE(t.in_fov);
  EXPECT_EQ(t.visible_fraction, 0.0);
  ASSERT_TRUE(t.corners[0].has_value());  // in front: projected, but outside the image
  EXPECT_GT(t.corners[0]->x(), 640.0);
}

TEST(Visibility, BehindCamera) {
  // Facing the camera from behind it (z < 0), so only the camera's orientation excludes it.
  const Pose g = make_pose(Vec3(0, 0, -1.2), Vec3::Zero());
  Renderer r(testing::single_tag_scene(g));
  const FrameTruth t = r.truth(0, 0);
  EXPECT_FALSE(t.in_fov);
  EXPECT_EQ(t.visible_fraction, 0.0);
  for (const auto& c : t.corners) EXPECT_FALSE(c.has_value());
}

TEST(Visibility, FullyOccluded) {
  auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.2), Vec3::Zero()));
  s.occluders.push_back(wall(Vec3(0, 0, 0.8), Vec3(0.5, 0.5, 0.02)));
  Renderer r(s);
  const FrameTruth t = r.truth(0, 0);
  EXPECT_TRUE(t.in_fov);  // in view, but hidden
  EXPECT_EQ(t.visible_fraction, 0.0);
}

TEST(Visibility, HalfOccluded) {
  auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.2), Vec3(0, 0, 0.3)));
  // Wall covering x < 0 at z = 0.8: hides the part of the tag left of the optical axis' plane.
  s.occluders.push_back(wall(Vec3(-0.5, 0, 0.8), Vec3(1.0, 1.0, 0.02)));
  Renderer r(s);
  const FrameTruth t = r.truth(0, 0);
  EXPECT_TRUE(t.in_fov);
  EXPECT_NEAR(t.visible_fraction, 0.5, 0.1);
  // The image agrees: the tag's left image half shows the (uniform grey) wall, the right half the
  // tag.
  const cv::Mat img = r.render(0, 0);
  const int row = 240;
  int dark_left = 0, dark_right = 0;
  for (int c = 250; c < 318; ++c) dark_left += img.at<uint8_t>(row, c) < 60;
  for (int c = 322; c < 390; ++c) dark_right += img.at<uint8_t>(row, c) < 60;
  EXPECT_EQ(dark_left, 0);
  EXPECT_GT(dark_right, 5);
}

TEST(Visibility, MovingOccluderChangesVisibilityOverTime) {
  auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1.2), Vec3::Zero()));
  Body b = wall(Vec3::Zero(), Vec3(0.5, 0.5, 0.02));
  Trajectory tr;
  tr.kind = Trajectory::Kind::Twist;
  tr.g0 = make_pose(Vec3(-1.0, 0, 0.8), Vec3::Zero());
  tr.twist << 1.0, 0, 0, 0, 0, 0;  // 1 m/s along x: passes in front of the tag at t = 1 s
  b.motion = tr;
  s.occluders.push_back(b);
  s.fps = 10;
  s.frames = 21;
  Renderer r(s);
  EXPECT_DOUBLE_EQ(r.truth(0, 0).visible_fraction, 1.0);
  EXPECT_EQ(r.truth(0, 10).visible_fraction, 0.0);
  EXPECT_DOUBLE_EQ(r.truth(0, 20).visible_fraction, 1.0);
}

}  // namespace
}  // namespace netvmo::render

namespace netvmo::render {
namespace {

// look_at builds an OpenCV camera (x right, y down, z forward): a point up and to the right of
// the viewing direction appears above and right of the principal point.
TEST(Camera, LookAtIsUprightAndRightHanded) {
  const Pose g_wi = look_at(Vec3(0, -2, 1), Vec3(0, 0, 1), Vec3(0, 0, 1));
  EXPECT_NEAR(g_wi.linear().determinant(), 1.0, 1e-12);
  Intrinsics k;
  const auto uv = k.project(g_wi.inverse() * Vec3(0.1, 0, 1.2));
  ASSERT_TRUE(uv.has_value());
  EXPECT_GT(uv->x(), k.cx);
  EXPECT_LT(uv->y(), k.cy);
}

// Distortion: undistort inverts distort, and project() matches the OpenCV model.
TEST(Camera, DistortionRoundTrip) {
  Intrinsics k;
  k.dist = {-0.08, 0.02, 0.001, -0.001, 0.003};
  for (double x : {-0.5, -0.1, 0.0, 0.3, 0.55})
    for (double y : {-0.4, 0.0, 0.2, 0.4}) {
      const Vec2 xd = k.distort(Vec2(x, y));
      const auto back = k.undistort(xd);
      ASSERT_TRUE(back.has_value());
      EXPECT_NEAR(back->x(), x, 1e-10);
      EXPECT_NEAR(back->y(), y, 1e-10);
    }
  // Radial-only value by hand: r^2 = 0.25, factor 1 - 0.08*0.25 + 0.02*0.0625 + 0.003*0.015625.
  k.dist = {-0.08, 0.02, 0, 0, 0.003};
  const double f = 1 - 0.02 + 0.00125 + 0.003 * 0.015625;
  EXPECT_NEAR(k.distort(Vec2(0.3, 0.4)).x(), 0.3 * f, 1e-15);
}

}  // namespace
}  // namespace netvmo::render
