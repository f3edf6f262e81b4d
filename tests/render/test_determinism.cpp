// Determinism: the same scene and seed give byte-identical images, whatever the thread count;
// another seed gives a different image.
#include <gtest/gtest.h>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

SceneDescription noisy_scene(std::uint64_t seed, int threads) {
  auto s = testing::single_tag_scene(testing::facing_pose(Vec3(0.1, 0, 1.5), Vec3(0.2, 0.3, 0.1)), 4);
  s.imaging.noise = true;
  s.imaging.seed = seed;
  s.imaging.threads = threads;
  s.target.motion.kind = Trajectory::Kind::Twist;
  s.target.motion.g0 = s.target.motion.g0;
  s.target.motion.twist << 0.1, 0, 0, 0, 0.2, 0;
  Body floor;
  Shape p;
  p.kind = Shape::Kind::Plane;
  p.size = Vec3(6, 6, 0);
  p.pose = make_pose(Vec3(0, 0.6, 0), Vec3(M_PI / 2, 0, 0));
  p.material.pattern = Material::Pattern::Noise;
  p.material.albedo = 0.5;
  p.material.albedo2 = 0.3;
  p.material.scale = 0.1;
  floor.shapes.push_back(p);
  s.occluders.push_back(floor);
  s.frames = 3;
  return s;
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

TEST(Determinism, SameSeedSameBytes) {
  Renderer a(noisy_scene(42, 2)), b(noisy_scene(42, 1));
  for (int f : {0, 2}) {
    const cv::Mat ia = a.render(0, f), ib = b.render(0, f);
    EXPECT_TRUE(identical(ia, ib)) << "frame " << f;
    EXPECT_TRUE(identical(ia, a.render(0, f))) << "re-render of frame " << f;
  }
}

TEST(Determinism, OtherSeedOtherNoise) {
  Renderer a(noisy_scene(42, 2)), b(noisy_scene(43, 2));
  EXPECT_FALSE(identical(a.render(0, 0), b.render(0, 0)));
}

}  // namespace
}  // namespace netvmo::render
