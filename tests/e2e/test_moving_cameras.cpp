// Moving cameras end to end: datasets/moving_cameras.yaml rendered at test time into a dataset
// folder (cameras.csv: believed poses per image, truth_cameras.csv: true ones), then `run`'s
// pipeline on it with the camera body velocities V_wi of (eq:EsRRBM) and without them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "netvmo/render/renderer.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

namespace {

// The scene rendered into a dataset folder `dir`.
void render_dataset(const render::SceneDescription& scene, const fs::path& dir) {
  render::Renderer renderer(scene);
  io::DatasetSettings o;
  o.progress = false;
  io::write_dataset(renderer, dir, o);
}

// The worst of every camera's final error to g* (the last frame's), and each one.
run::PoseError final_errors(const run::ImageRunResult& r, std::vector<run::PoseError>* per_camera) {
  const auto& last = r.history.back();
  run::PoseError w;
  for (const auto& c : last.cameras) {
    const auto e = run::pose_error(c.est_w, *last.g_star);
    if (per_camera) per_camera->push_back(e);
    w.position = std::max(w.position, e.position);
    w.orientation_deg = std::max(w.orientation_deg, e.orientation_deg);
  }
  return w;
}

// With V_wi every camera ends within 1 cm and 0.5 degrees of g*; with V_wi = 0 (the same run
// otherwise) the worst camera is at least 5 times further in position and orientation and misses
// 1 cm. Prints both worst errors after `label`.
void expect_converged_and_velocity_needed(const run::ImageRunResult& with_v,
                                          const run::ImageRunResult& without_v, const char* label) {
  std::vector<run::PoseError> each;
  const run::PoseError w = final_errors(with_v, &each);
  for (size_t i = 0; i < each.size(); ++i) {
    EXPECT_LT(each[i].position, 0.01) << label << ": camera " << i + 1;
    EXPECT_LT(each[i].orientation_deg, 0.5) << label << ": camera " << i + 1;
  }
  const run::PoseError w0 = final_errors(without_v, nullptr);
  std::printf(
      "%s, worst final error to g*: with V_wi %.2f mm / %.3f deg, V_wi = 0 %.2f mm / %.3f deg\n",
      label, 1e3 * w.position, w.orientation_deg, 1e3 * w0.position, w0.orientation_deg);
  EXPECT_GT(w0.position, 5.0 * w.position) << label;
  EXPECT_GT(w0.orientation_deg, 5.0 * w.orientation_deg) << label;
  EXPECT_GT(w0.position, 0.01) << label;
}

}  // namespace

// Cameras 1-3 move (a rail, a pan, an arc) and see the static tag; camera 4 moves, drifts and
// never sees it. With V_wi every camera ends within 1 cm and 0.5 degrees of g*; with V_wi = 0
// the estimates lag behind the cameras' motion (measured: docs/images.md, "Moving cameras").
TEST(EndToEnd, MovingCamerasConvergeToGStarAndNeedTheirVelocity) {
  const fs::path root = test::scratch_dir("moving_cameras");
  const fs::path dir = root / "ds";  // outputs go beside it: an --out inside a dataset is refused
  auto scene =
      io::load_render_scenario(fs::path(NETVMO_SOURCE_DIR) / "datasets" / "moving_cameras.yaml");
  scene.imaging.spp = 1;
  render_dataset(scene, dir);
  // The folder holds one believed and one true pose per camera image; frame 0's believed pose
  // is network.yaml's.
  const auto believed = io::read_camera_poses_csv(dir / "cameras.csv");
  const auto truth = io::read_camera_truth_csv(dir / "truth_cameras.csv");
  ASSERT_EQ(believed.size(), scene.cameras.size() * size_t(scene.frames));
  ASSERT_EQ(truth.size(), believed.size());
  auto source = sources::open_dataset_source(dir);
  ASSERT_TRUE(source->cameras_move());
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    EXPECT_TRUE(source->camera_believed(i, 0).isApprox(source->network().cameras[i].g_wi, 1e-9));
    EXPECT_TRUE(source->camera_truth(i, 60)->isApprox(scene.cameras[i].true_pose(2.0), 1e-9));
  }

  run::ImageRunSettings options;
  options.progress = false;
  const auto with_v = run::run_images(*source, options);
  options.ignore_camera_velocity = true;
  const auto without_v = run::run_images(*source, options);
  ASSERT_EQ(int(with_v.history.size()), scene.frames);
  ASSERT_TRUE(with_v.history.back().g_star.has_value());

  for (size_t i = 0; i < 4; ++i) {
    int seen = 0;
    for (const auto& f : with_v.history) seen += f.cameras[i].delta;
    if (i < 3)
      EXPECT_GE(seen, scene.frames - 2) << "camera " << i + 1 << " should see the tag";
    else
      EXPECT_EQ(seen, 0) << "camera 4 should never see the tag";
  }
  // Measured (spp 1): 2.3 mm / 0.33 deg with V_wi, 20.2 mm / 2.41 deg without, 8.9 and 7.3
  // times worse (docs/images.md, "Moving cameras", 2026-12-06); the test asks for 5 times and for
  // the V_wi = 0 run to miss the 1 cm bound that the run with V_wi meets.
  expect_converged_and_velocity_needed(with_v, without_v, "one clock");

  // Bad input on the command line: a cameras.csv without camera 2's frame 17 stops `run` with one
  // line naming the file, the camera and the frame, and writes no results; `launch` refuses
  // moving cameras.
  const std::string poses = test::slurp(dir / "cameras.csv");
  std::string cut = poses;
  const auto at = cut.find("\n2,17,");
  ASSERT_NE(at, std::string::npos);
  cut.erase(at + 1, cut.find('\n', at + 1) - at);
  { std::ofstream(dir / "cameras.csv") << cut; }
  const auto bad = test::run_netvmo(
      "run " + dir.string() + " --out " + (root / "out").string() + " --no-overlays --no-plots",
      root, 120);
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("cameras.csv: camera 2: no row for frame 17"), std::string::npos)
      << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_FALSE(fs::exists(root / "out" / "summary.json"));
  { std::ofstream(dir / "cameras.csv") << poses; }
  const auto launch = test::run_netvmo(
      "launch " + dir.string() + " --out " + (root / "launch").string() + " --no-overlays", root,
      120);
  EXPECT_NE(launch.code, 0);
  EXPECT_NE(launch.err.find("netvmo launch handles static cameras"), std::string::npos)
      << launch.err;
  fs::remove_all(root);
}

// The same scene with cameras 2 and 3 on their own clocks (25 frames/s from 13 ms, 15 frames/s
// from 47 ms; cameras 1 and 4 at the scene's 30): the run on the union of the image times, where
// each camera's believed pose and V_wi come from its own images' times, interpolated between
// them. With V_wi every camera ends within the bounds of the synchronised run above; with V_wi =
// 0 it lags as there (measured: docs/images.md, "Unsynchronised cameras").
TEST(EndToEnd, MovingCamerasOnTheirOwnClocksConvergeOnTheUnionOfTheirTimes) {
  const fs::path root = test::scratch_dir("moving_own_clocks");
  const fs::path dir = root / "ds";
  auto scene =
      io::load_render_scenario(fs::path(NETVMO_SOURCE_DIR) / "datasets" / "moving_cameras.yaml");
  scene.imaging.spp = 1;
  ASSERT_EQ(scene.cameras.size(), 4u);
  scene.cameras[1].fps = 25.0;
  scene.cameras[1].start = 0.013;
  scene.cameras[2].fps = 15.0;
  scene.cameras[2].start = 0.047;
  render_dataset(scene, dir);
  auto source = sources::open_dataset_source(dir);
  ASSERT_TRUE(source->cameras_move());
  ASSERT_TRUE(sources::clock_mismatch(*source));

  run::ImageRunSettings options;
  options.progress = false;
  const auto with_v = run::run_images(*source, options);
  options.ignore_camera_velocity = true;
  const auto without_v = run::run_images(*source, options);
  ASSERT_TRUE(with_v.union_of_timestamps);
  ASSERT_EQ(int(with_v.history.size()), scene.frames);
  ASSERT_TRUE(with_v.history.back().g_star.has_value());
  // Camera 4 never sees the tag; the others see it in nearly all of their own images.
  std::vector<int> images(4, 0), seen(4, 0);
  for (const auto& row : with_v.own_estimates) {
    ++images[row.camera];
    seen[row.camera] += row.delta ? 1 : 0;
  }
  for (size_t i = 0; i < 3; ++i) EXPECT_GE(seen[i], images[i] - 2) << "camera " << i + 1;
  EXPECT_EQ(seen[3], 0);
  // Every image up to the last grid time (89 / 30 s) taken once, at its own time.
  std::vector<int> up_to_end(4, 0);
  for (const auto& r : io::read_timestamps_csv(dir / "timestamps.csv"))
    if (r.t <= (scene.frames - 1) / 30.0 + 1e-9) ++up_to_end[size_t(r.camera - 1)];
  EXPECT_EQ(images, up_to_end);
  EXPECT_EQ(up_to_end[2], 44);  // 0.047 + k / 15 s for k = 0..43

  expect_converged_and_velocity_needed(with_v, without_v, "own clocks");
  fs::remove_all(root);
}
