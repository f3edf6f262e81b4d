// Image times of recorded folders: a video's own timestamps (OpenCV's CAP_PROP_POS_MSEC), the
// note when a camera's times fall back to frame / fps, and `run` on the union of timestamps when
// the cameras' common clock is not the dataset's fps.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

namespace {

bool any_note_contains(const std::vector<std::string>& notes, const std::string& a,
                       const std::string& b) {
  for (const auto& n : notes)
    if (n.find(a) != n.npos && n.find(b) != n.npos) return true;
  return false;
}

}  // namespace

// Two cameras' MJPG videos written by cv::VideoWriter at 12.5 frames/s in a dataset that says
// 30: each image's time is the video's (k * 80 ms), not frame / 30, and `run` integrates over
// those times (the union of timestamps: 6 images 80 ms apart span 13 grid times at 30/s).
TEST(Timestamps, AVideosOwnTimestampsGiveItsImageTimes) {
  const auto dir = netvmo::testing::fresh_dir("ts_video");
  auto spec = netvmo::testing::simple_dataset_spec(2, 6, /*video=*/true);
  spec.fps = 12.5;  // the writer's frame rate, stored in the container
  netvmo::testing::write_synth_dataset(dir, spec);
  auto net = io::load_network_config(dir / "network.yaml");
  ASSERT_EQ(net.fps, 12.5);
  net.fps = 30;
  { std::ofstream(dir / "network.yaml") << io::network_yaml(net); }

  const auto ds = sources::open_dataset(dir);
  for (size_t i = 0; i < 2; ++i) {
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(ds.frame_time(i, k), k / 12.5, 1e-9) << i << " " << k;
    EXPECT_TRUE(any_note_contains(ds.notes, "camera " + std::to_string(i + 1),
                                  "its times are its video's own timestamps"));
  }
  auto source = sources::open_dataset_source(dir);
  EXPECT_FALSE(sources::clock_mismatch(*source));  // one clock, but not 30 frames/s
  const auto irregular = sources::irregular_clock(*source);
  ASSERT_TRUE(irregular);
  EXPECT_NE(irregular->find("frame 1 is at t = 0.08 s"), std::string::npos) << *irregular;

  run::ImageRunSettings options;
  options.progress = false;
  const auto r = run::run_images(*source, options);
  EXPECT_TRUE(r.union_of_timestamps);
  ASSERT_EQ(r.history.size(), 13u);  // t = 0 .. 0.4 s at 1/30 s
  EXPECT_NEAR(r.history.back().t, 0.4, 1e-12);
  ASSERT_EQ(r.own_estimates.size(), 12u);
  EXPECT_NEAR(r.own_estimates.back().t, 0.4, 1e-9);
  // At t = 0.2 s (grid time 6) each camera holds its image 2 (at 0.16 s).
  EXPECT_EQ(r.source_frames[6], (std::vector<int>{2, 2}));
}

// A video at the dataset's fps keeps exactly frame / fps (containers round their times), and
// the synchronised run; a camera without timestamps.csv rows or video times runs on frame / its
// fps, and `netvmo run` says so in its log (a note on stderr).
TEST(Timestamps, TimesFallBackToFrameOverFpsWithANote) {
  const auto dir = netvmo::testing::fresh_dir("ts_note");
  {
    auto spec = netvmo::testing::simple_dataset_spec(2, 4, /*video=*/true);
    spec.video_ext = ".mkv";  // Matroska stores times in ms: 33, 67, 100 ms
    spec.video_fourcc = "FFV1";
    netvmo::testing::write_synth_dataset(dir / "video", spec);
    const auto ds = sources::open_dataset(dir / "video");
    EXPECT_EQ(ds.frame_time(1, 1), 1 / 30.0);
    EXPECT_TRUE(any_note_contains(ds.notes, "camera 2", "within 1 ms, taken exactly"));
    EXPECT_FALSE(sources::irregular_clock(*sources::open_dataset_source(dir / "video")));
  }
  netvmo::testing::write_synth_dataset(dir / "ds", netvmo::testing::simple_dataset_spec(2, 4));
  const auto ds = sources::open_dataset(dir / "ds");
  EXPECT_TRUE(any_note_contains(ds.notes, "no " + (dir / "ds" / "timestamps.csv").string(),
                                "camera 2: its times are frame index / its fps (30 frames/s)"));
  const auto r = test::run_netvmo("run " + (dir / "ds").string() + " --out " +
                                      (dir / "out").string() + " --no-overlays --no-plots",
                                  dir, 60);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("note: no " + (dir / "ds" / "timestamps.csv").string() +
                       ": camera 1: its times are frame index / its fps"),
            std::string::npos)
      << r.err;
}
