// Several targets on images rendered at test time (datasets/two_targets.yaml): two tagged bodies
// moving independently, each seen by a different subset of 5 cameras, decided in one front-end
// pass per image, each with its own networked observer. Each target's estimates converge to its
// own g* at every camera, and hiding one target does not disturb the other's estimates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

namespace {
const fs::path kScenario = fs::path(NETVMO_SOURCE_DIR) / "datasets" / "two_targets.yaml";
constexpr int kFrames = 60;  // 2 s: both targets have moved and stopped (0.8 s and 0.7 s)

run::ImageRunSettings options() {
  run::ImageRunSettings o;
  o.progress = false;
  // k_e = 5: the estimates start at each camera's own fictitious target (7-19 cm apart) and
  // follow the motion with a lag; after the targets stop, the error to g* decays about as
  // exp(-k_e t) down to the orientation offset (~0.5 deg here, the paper's epsilon-level). With
  // the paper's k_e = 1 the 1.2 s of rest are not enough (measured with `netvmo run` on the
  // rendered scenario: 42 mm at its end, 11 mm with k_e = 3 at 2 s, 3 mm with k_e = 5).
  o.runner.k_e = 5.0;
  return o;
}

run::ImageRunResult run_scene(const render::SceneDescription& scene) {
  auto source = sources::make_render_source(scene, kFrames);
  return run::run_images(*source, options());
}

int seen_frames(const run::ImageRunResult& r, size_t camera) {
  int seen = 0;
  for (const auto& f : r.history) seen += f.cameras[camera].delta;
  return seen;
}
}  // namespace

TEST(SeveralTargets, EachConvergesToItsOwnGStarAndHidingOneLeavesTheOther) {
  const auto scene = io::load_render_scenario(kScenario);
  ASSERT_EQ(scene.targets.size(), 2u);
  const auto r = run_scene(scene);
  ASSERT_EQ(r.target_count(), 2u);
  // Cameras 1, 2 see target A (ids 0, 1) only, 4, 5 target B (id 2) only, 3 both: every delta
  // comes from the front end, target by target.
  const std::vector<std::vector<bool>> sees = {{true, true, true, false, false},
                                               {false, false, true, true, true}};
  for (size_t j = 0; j < 2; ++j) {
    const auto& tr = r.target(j);
    ASSERT_EQ(int(tr.history.size()), kFrames);
    for (size_t i = 0; i < 5; ++i) {
      if (sees[j][i]) {
        EXPECT_GE(seen_frames(tr, i), kFrames - 2) << "target " << j << " camera " << i + 1;
      } else {
        EXPECT_EQ(seen_frames(tr, i), 0) << "target " << j << " camera " << i + 1;
      }
    }
    // Every camera (those that never see the target included) ends at its own target's g*,
    // far closer than its own independent observer or PnP (fictitious targets 7-19 cm apart).
    const auto& last = tr.history.back();
    ASSERT_TRUE(last.g_star.has_value());
    for (size_t i = 0; i < 5; ++i) {
      ASSERT_TRUE(last.cameras[i].initialized);
      const auto e = run::pose_error(last.cameras[i].est_w, *last.g_star);
      std::printf("target %zu camera %zu: %.2f mm, %.3f deg from its g*\n", j, i + 1,
                  1e3 * e.position, e.orientation_deg);
      EXPECT_LT(e.position, 0.01) << "target " << j << " camera " << i + 1;
      EXPECT_LT(e.orientation_deg, 1.0) << "target " << j << " camera " << i + 1;
      if (last.cameras[i].pnp_w) {
        EXPECT_LT(e.position, 0.5 * run::pose_error(*last.cameras[i].pnp_w, *last.g_star).position);
      }
    }
    // Each g* is its own target's, not the other's (the targets are 1.7 m apart).
    const auto other = r.target(1 - j).history.back().g_star;
    EXPECT_GT(run::pose_error(*last.g_star, *other).position, 1.0);
  }

  // Target B hidden under the floor for the whole run: still listed, never detected, and target
  // A's estimates stay where they were.
  auto hidden = scene;
  render::Pose below = render::Pose::Identity();
  below.translation() = render::Vec3(0.9, 0.0, -2.0);
  hidden.targets[1].motion = render::Trajectory::fixed(below);
  const auto h = run_scene(hidden);
  ASSERT_EQ(h.target_count(), 2u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(seen_frames(h.target(1), i), 0);
  double dp = 0.0, dr = 0.0;
  for (int k = 0; k < kFrames; ++k)
    for (size_t i = 0; i < 5; ++i) {
      const auto& a = r.history[size_t(k)].cameras[i];
      const auto& b = h.history[size_t(k)].cameras[i];
      ASSERT_EQ(a.delta, b.delta) << "frame " << k << " camera " << i + 1;
      const auto e = run::pose_error(b.est_w, a.est_w);
      dp = std::max(dp, e.position);
      dr = std::max(dr, e.orientation_deg);
    }
  std::printf("target A with target B hidden: at most %.3g mm, %.3g deg from the full run\n",
              1e3 * dp, dr);
  EXPECT_LT(dp, 1e-4);
  EXPECT_LT(dr, 0.01);
}
