// Determinism: the same scene and seed give byte-identical images, whatever the thread count;
// another seed gives a different image.
#include <gtest/gtest.h>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

SceneDescription noisy_scene(std::uint64_t seed, int threads,
                             Imaging::Sampling sampling = Imaging::Sampling::Grid) {
  auto s =
      testing::single_tag_scene(testing::facing_pose(Vec3(0.1, 0, 1.5), Vec3(0.2, 0.3, 0.1)), 4);
  s.imaging.sampling = sampling;
  s.imaging.noise = true;
  s.imaging.seed = seed;
  s.imaging.threads = threads;
  s.target().motion.kind = Trajectory::Kind::Twist;
  s.target().motion.g0 = s.target().motion.g0;
  s.target().motion.twist << 0.1, 0, 0, 0, 0.2, 0;
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
  for (const auto sampling : {Imaging::Sampling::Grid, Imaging::Sampling::Jittered}) {
    Renderer a(noisy_scene(42, 2, sampling)), b(noisy_scene(42, 1, sampling));
    for (int f : {0, 2}) {
      const cv::Mat ia = a.render(0, f), ib = b.render(0, f);
      EXPECT_TRUE(identical(ia, ib)) << "frame " << f;
      EXPECT_TRUE(identical(ia, a.render(0, f))) << "re-render of frame " << f;
    }
  }
}

TEST(Determinism, OtherSeedOtherNoise) {
  Renderer a(noisy_scene(42, 2)), b(noisy_scene(43, 2));
  EXPECT_FALSE(identical(a.render(0, 0), b.render(0, 0)));
}

// Jittered sampling moves the samples, not the noise: without noise, the same seed gives the
// same image and another seed another one; grid sampling does not depend on the seed. Also
// through a lens with distortion, whose rays are tabled per (pixel, sample).
TEST(Determinism, JitteredSamplesFollowTheSeed) {
  for (const double k1 : {0.0, -0.1}) {
    auto clean = [k1](std::uint64_t seed, Imaging::Sampling sampling) {
      auto s = noisy_scene(seed, 2, sampling);
      s.imaging.noise = false;
      s.cameras[0].intrinsics.dist[0] = k1;
      return Renderer(s).render(0, 1);
    };
    const auto J = Imaging::Sampling::Jittered, G = Imaging::Sampling::Grid;
    EXPECT_TRUE(identical(clean(5, J), clean(5, J))) << "k1 " << k1;
    EXPECT_FALSE(identical(clean(5, J), clean(6, J))) << "k1 " << k1;
    EXPECT_FALSE(identical(clean(5, J), clean(5, G))) << "k1 " << k1;
    EXPECT_TRUE(identical(clean(5, G), clean(6, G))) << "k1 " << k1;
  }
}

}  // namespace
}  // namespace netvmo::render

#include <thread>

namespace netvmo::render {
namespace {

// Rendering different cameras of one frame from several threads gives the same bytes as
// rendering them one after the other; a call for another frame switches the frame safely.
TEST(Determinism, ConcurrentCamerasMatchSequential) {
  auto s = noisy_scene(9, 1);
  CameraSpec second = s.cameras[0];
  second.id = 2;
  second.g_wi_true = make_pose(Vec3(0.3, 0, 0), Vec3(0, -0.2, 0));
  s.cameras.push_back(second);
  Renderer seq(s), par(s);
  const cv::Mat a0 = seq.render(0, 1), a1 = seq.render(1, 1), b2 = seq.render(0, 2);
  cv::Mat p0, p1, p2;
  std::thread t0([&] { p0 = par.render(0, 1); });
  std::thread t1([&] { p1 = par.render(1, 1); });
  std::thread t2([&] { p2 = par.render(0, 2); });
  t0.join();
  t1.join();
  t2.join();
  EXPECT_TRUE(identical(a0, p0));
  EXPECT_TRUE(identical(a1, p1));
  EXPECT_TRUE(identical(b2, p2));
  EXPECT_FALSE(identical(a0, a1));
}

}  // namespace
}  // namespace netvmo::render

namespace netvmo::render {
namespace {

// Reusing a static scene's radiance gives exactly the image a full trace gives, and a moved
// body is never served from the cache.
TEST(Determinism, StaticSceneReuseIsByteIdentical) {
  for (const auto sampling : {Imaging::Sampling::Grid, Imaging::Sampling::Jittered})
    for (bool moving : {false, true}) {
      auto scene = noisy_scene(7, 2, sampling);
      if (!moving) scene.target().motion = Trajectory::fixed(scene.target().motion.g0);
      auto fresh_scene = scene;
      fresh_scene.imaging.reuse_radiance = false;
      Renderer cached(scene), fresh(fresh_scene);
      for (int f = 0; f < 3; ++f) {
        const cv::Mat a = cached.render(0, f), b = fresh.render(0, f);
        EXPECT_TRUE(identical(a, b)) << (moving ? "moving" : "static") << " frame " << f;
      }
      // The frames differ (new noise, or a moved target), so nothing stale was served.
      EXPECT_FALSE(identical(cached.render(0, 1), cached.render(0, 2)));
    }
}

}  // namespace
}  // namespace netvmo::render
