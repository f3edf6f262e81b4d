// Unsynchronised cameras end to end: datasets/unsync.yaml (30, 25 and 15 frames/s, first images
// at 0, 13 and 47 ms, a static target) rendered at test time, `run`'s pipeline on the union of
// the cameras' timestamps, against g* and against the synchronised rendering of the same scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

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

// datasets/unsync.yaml at 1 sample per pixel, on its cameras' own clocks or all on the scene's.
fs::path render_unsync(const fs::path& dir, bool own_clocks) {
  auto scene = io::load_render_scenario(fs::path(NETVMO_SOURCE_DIR) / "datasets" / "unsync.yaml");
  scene.imaging.spp = 1;
  if (!own_clocks)
    for (auto& c : scene.cameras) {
      c.fps.reset();
      c.start = 0.0;
    }
  render::Renderer renderer(scene);
  io::DatasetSettings o;
  o.progress = false;
  io::write_dataset(renderer, dir, o);
  return dir;
}

// A camera's per-image PnP noise: the RMS of the change between consecutive PnP poses over
// sqrt(2) (independent noise of standard deviation s changes by s sqrt(2)), position [m] and
// angle [deg]; a static scene, so the pose itself does not change.
run::PoseError pnp_noise(const run::ImageRunResult& r, size_t i) {
  double p2 = 0, r2 = 0;
  int n = 0;
  for (size_t k = 1; k < r.history.size(); ++k) {
    const auto& a = r.history[k - 1].cameras[i].pnp_w;
    const auto& b = r.history[k].cameras[i].pnp_w;
    if (!a || !b) continue;
    const auto e = run::pose_error(*b, *a);
    p2 += e.position * e.position;
    r2 += e.orientation_deg * e.orientation_deg;
    ++n;
  }
  return {std::sqrt(p2 / std::max(n, 1) / 2), std::sqrt(r2 / std::max(n, 1) / 2)};
}

}  // namespace

TEST(Unsync, ThreeRatesConvergeToGStarAndAgreeWithTheSynchronisedRendering) {
  const fs::path root = test::scratch_dir("unsync");
  const fs::path own = render_unsync(root / "own", true), one = render_unsync(root / "one", false);

  // Each camera's own images and times: 2 s at 30, 25 and 15 frames/s from 0, 13 and 47 ms.
  std::map<int, std::vector<double>> times;
  for (const auto& r : io::read_timestamps_csv(own / "timestamps.csv"))
    times[r.camera].push_back(r.t);
  ASSERT_EQ(times[1].size(), 60u);
  ASSERT_EQ(times[2].size(), 50u);
  ASSERT_EQ(times[3].size(), 30u);
  EXPECT_DOUBLE_EQ(times[2][10], 0.013 + 10 / 25.0);
  EXPECT_DOUBLE_EQ(times[3][29], 0.047 + 29 / 15.0);
  EXPECT_EQ(io::read_target_csv(own / "target.csv").size(), 140u);  // every image time

  auto source = sources::open_dataset_source(own);
  auto sync_provider = sources::open_dataset_source(one);
  EXPECT_EQ(source->network().camera_fps(1), 25.0);
  EXPECT_EQ(source->network().camera_fps(2), 15.0);
  ASSERT_TRUE(sources::clock_mismatch(*source));
  ASSERT_FALSE(sources::clock_mismatch(*sync_provider));
  ASSERT_FALSE(sources::irregular_clock(*sync_provider));

  run::ImageRunSettings options;
  options.progress = false;
  const auto u = run::run_images(*source, options);
  const auto s = run::run_images(*sync_provider, options);
  ASSERT_TRUE(u.union_of_timestamps);
  ASSERT_FALSE(s.union_of_timestamps);

  // Every image up to the last grid time (59 / 30 s) once, in time order, at its own time
  // (never paired by index).
  size_t used = 0;
  for (const auto& [id, t] : times)
    used += static_cast<size_t>(
        std::count_if(t.begin(), t.end(), [](double x) { return x <= 59 / 30.0 + 1e-9; }));
  EXPECT_EQ(used, 138u);  // camera 2's and 3's last images come after it
  ASSERT_EQ(u.own_estimates.size(), used);
  for (size_t e = 0; e < u.own_estimates.size(); ++e) {
    const auto& row = u.own_estimates[e];
    const int id = static_cast<int>(row.camera) + 1;
    EXPECT_EQ(row.t, times[id][static_cast<size_t>(row.frame)]);
    if (e) {
      EXPECT_LE(u.own_estimates[e - 1].t, row.t);
    }
  }
  // The regular grid k / 30 s; each camera holds its latest image at or before a grid time.
  ASSERT_EQ(u.history.size(), 60u);
  for (size_t k = 0; k < u.history.size(); ++k) {
    EXPECT_NEAR(u.history[k].t, k / 30.0, 1e-12);
    for (int id = 1; id <= 3; ++id)
      EXPECT_EQ(u.source_frames[k][size_t(id - 1)], run::latest_at_or_before(times[id], k / 30.0))
          << "grid " << k << " camera " << id;
  }

  // Within 1 cm and 0.5 degrees of g* at the end.
  const auto& last = u.history.back();
  ASSERT_TRUE(last.g_star.has_value());
  for (size_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(last.cameras[i].initialized);
    const auto e = run::pose_error(last.cameras[i].est_w, *last.g_star);
    EXPECT_LT(e.position, 0.01) << "camera " << i + 1;
    EXPECT_LT(e.orientation_deg, 0.5) << "camera " << i + 1;
  }
  // Agreement with the synchronised rendering of the same static scene: both runs estimate the
  // same g* (the same believed poses and target), from images with independent sensor noise.
  // Each final estimate is the observer's low-pass (time constant 1 / k_e = 1 s) of many PnP
  // poses, so the two differ by much less than one image's PnP noise: the tolerance is the
  // smallest camera's per-image PnP noise in the synchronised run.
  run::PoseError tol{1e9, 1e9};
  for (size_t i = 0; i < 3; ++i) {
    const auto n = pnp_noise(s, i);
    tol.position = std::min(tol.position, n.position);
    tol.orientation_deg = std::min(tol.orientation_deg, n.orientation_deg);
  }
  for (size_t i = 0; i < 3; ++i) {
    const auto d = run::pose_error(last.cameras[i].est_w, s.history.back().cameras[i].est_w);
    std::printf(
        "camera %zu: to g* %.2f mm %.3f deg; union vs synchronised %.3f mm %.4f deg "
        "(tolerance %.3f mm %.4f deg)\n",
        i + 1, 1e3 * run::pose_error(last.cameras[i].est_w, *last.g_star).position,
        run::pose_error(last.cameras[i].est_w, *last.g_star).orientation_deg, 1e3 * d.position,
        d.orientation_deg, 1e3 * tol.position, tol.orientation_deg);
    EXPECT_LT(d.position, tol.position) << "camera " << i + 1;
    EXPECT_LT(d.orientation_deg, tol.orientation_deg) << "camera " << i + 1;
  }

  // Outputs: estimates.csv has a row per image with its time, energies.csv the grid, and
  // summary.json says the run was on the union of timestamps.
  const fs::path out = root / "run";
  const auto summary = run::write_run_outputs(out, *source, options, u);
  EXPECT_TRUE(summary.contains("clock"));
  EXPECT_EQ(summary["frames"].get<int>(), 60);
  const std::string est = test::slurp(out / "estimates.csv");
  EXPECT_EQ(std::count(est.begin(), est.end(), '\n'), static_cast<long>(used) + 1);
  EXPECT_NE(est.find("\n0,0.013,2,"), std::string::npos);
  EXPECT_FALSE(run::run_summary(*sync_provider, options, s).contains("clock"));
}
