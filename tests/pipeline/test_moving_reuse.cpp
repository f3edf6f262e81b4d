// Radiance reuse on moving scenes: re-tracing only where a moved body or its shadow can reach
// gives, on every frame and camera, the image a full trace gives (datasets/moving_target.yaml at
// a quarter of its resolution so that every frame fits in a few seconds).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"

namespace {

using netvmo::render::Light;
using netvmo::render::Renderer;
using netvmo::render::SceneDescription;

// A shipped scenario at a quarter of its resolution.
SceneDescription quarter(const char* name) {
  auto scene = netvmo::io::load_render_scenario(std::filesystem::path(NETVMO_SOURCE_DIR) /
                                                "datasets" / name);
  for (auto& cam : scene.cameras) {
    auto& K = cam.intrinsics;
    K.width /= 4;
    K.height /= 4;
    K.fx /= 4;
    K.fy /= 4;
    K.cx = (K.cx + 0.5) / 4 - 0.5;
    K.cy = (K.cy + 0.5) / 4 - 0.5;
  }
  return scene;
}

SceneDescription moving_target_quarter() {
  return quarter("moving_target.yaml");
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

// Renders frames 0..frames-1 and then frame 0 again (every body jumps back) with and without
// reuse; every image must match. Also checks that reuse happened: some images traced only part
// of their packets.
void expect_reuse_exact(const SceneDescription& scene, int frames, const std::string& what) {
  auto full_scene = scene;
  full_scene.imaging.reuse_radiance = false;
  Renderer reused(scene), full(full_scene);
  int partial = 0, mismatches = 0;
  for (int k = 0; k <= frames; ++k) {
    const int frame = k < frames ? k : 0;
    for (int c = 0; c < reused.camera_count(); ++c) {
      const cv::Mat a = reused.render(c, frame), b = full.render(c, frame);
      // Lit images (a blank renderer would match itself): the background alone is 0.6.
      EXPECT_GT(cv::mean(b)[0], 40.0) << what << ": camera " << c << " frame " << frame;
      if (!identical(a, b)) {
        ++mismatches;
        ADD_FAILURE() << what << ": camera " << scene.cameras[size_t(c)].id << " frame " << frame
                      << " (step " << k << ") differs from a full trace";
      }
      const double traced = reused.traced_fraction(c);
      if (k > 0 && traced > 0 && traced < 1) ++partial;
      EXPECT_DOUBLE_EQ(full.traced_fraction(c), 1.0);
    }
    if (mismatches > 5) return;
  }
  EXPECT_GT(partial, frames) << what << ": radiance was hardly ever reused";
}

TEST(MovingReuse, EveryFrameMatchesAFullTrace) {
  auto scene = moving_target_quarter();
  scene.imaging.spp = 1;
  expect_reuse_exact(scene, scene.frames, "moving_target, 1 spp");
}

// 2 samples per pixel (pixel blocks that do not fill whole packets) and a point light, whose
// shadow rays are segments.
TEST(MovingReuse, PointLightAndTwoSamplesMatchAFullTrace) {
  auto scene = moving_target_quarter();
  scene.imaging.spp = 2;
  Light point;
  point.kind = Light::Kind::Point;
  point.position = netvmo::render::Vec3(0.5, -1.0, 2.8);
  point.intensity = 4.0;
  scene.lights.push_back(point);
  expect_reuse_exact(scene, 40, "moving_target, 2 spp, point light");
}

}  // namespace

namespace {

// A moving camera re-traces its whole image (every ray changed) while the static cameras of the
// same renderer keep reusing theirs: moving_cameras.yaml at a quarter of its resolution, every
// frame byte-identical to a full trace.
TEST(MovingReuse, MovingCameraRetracesItsWholeImage) {
  auto scene = quarter("moving_cameras.yaml");
  scene.imaging.spp = 1;
  scene.cameras[2].motion.reset();  // camera 3 stands still at its first pose
  ASSERT_FALSE(scene.cameras[2].moving());
  ASSERT_TRUE(scene.cameras[0].moving());
  auto full_scene = scene;
  full_scene.imaging.reuse_radiance = false;
  Renderer reused(scene), full(full_scene);
  for (int frame = 0; frame < 12; ++frame)
    for (int c = 0; c < reused.camera_count(); ++c) {
      const cv::Mat a = reused.render(c, frame), b = full.render(c, frame);
      EXPECT_GT(cv::mean(b)[0], 20.0) << "camera " << c << " frame " << frame;  // lit, not blank
      EXPECT_TRUE(identical(a, b)) << "camera " << c << " frame " << frame;
      if (frame == 0) continue;
      if (scene.cameras[size_t(c)].moving())
        EXPECT_DOUBLE_EQ(reused.traced_fraction(c), 1.0) << "camera " << c << " frame " << frame;
      else
        EXPECT_DOUBLE_EQ(reused.traced_fraction(c), 0.0) << "camera " << c << " frame " << frame;
    }
}

}  // namespace
