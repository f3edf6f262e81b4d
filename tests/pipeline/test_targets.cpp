// Several targets: network.yaml's `targets:` (reading, writing, bad input) and the front end
// deciding every target in one pass (one observation per target, each by its own tags).
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using test::expect_input_error;

const char* kTwoTargets =
    "fps: 30\n"
    "targets:\n"
    "  - {family: tag36h11, id: 0, size: 0.2,\n"
    "     bundle: [{id: 1, size: 0.2, p: [0.256066, 0, -0.106066], r: [0, 0.785398, 0]}]}\n"
    "  - {family: tag36h11, id: 4, size: 0.1}\n"
    "cameras:\n"
    "  - {id: 1, p_wi: [0, 0, 0], r_wi: [0, 0, 0]}\n"
    "edges: []\n";

fs::path write_network(const fs::path& dir, const std::string& text) {
  return test::write_text(dir / "network.yaml", text);
}

std::string with(const std::string& from, const std::string& to) {
  return test::replaced(kTwoTargets, from, to);
}
}  // namespace

TEST(Targets, NetworkYamlReadsAndWritesSeveralTargets) {
  const auto dir = test::scratch_dir("targets_ok");
  const auto n = io::load_network_config(write_network(dir, kTwoTargets));
  ASSERT_EQ(n.targets.size(), 2u);
  EXPECT_EQ(n.target().id, 0);
  EXPECT_EQ(n.targets[0].tag_count(), 2u);
  EXPECT_EQ(n.targets[1].id, 4);
  EXPECT_EQ(n.targets[1].size, 0.1);
  EXPECT_TRUE(n.targets[1].bundle.empty());
  const std::string text = io::network_yaml(n);
  EXPECT_NE(text.find("targets:"), std::string::npos);
  const auto back = io::load_network_config(write_network(dir, text));
  ASSERT_EQ(back.targets.size(), 2u);
  EXPECT_EQ(back.targets[1].id, 4);
  EXPECT_EQ(back.targets[0].bundle.size(), 1u);
  EXPECT_TRUE(back.targets[0].tag_pose(1).isApprox(n.targets[0].tag_pose(1), 1e-11));
  // One target is written in the single-target form.
  io::NetworkConfig one = n;
  one.targets.resize(1);
  EXPECT_EQ(io::network_yaml(one).find("targets:"), std::string::npos);
  EXPECT_NE(io::network_yaml(one).find("target:"), std::string::npos);
}

TEST(Targets, BadTargetListsGiveOneLineNamingTheEntry) {
  const auto dir = test::scratch_dir("targets_bad");
  const auto load = [&](const std::string& text) {
    return [&dir, text] { io::load_network_config(write_network(dir, text)); };
  };
  // The same id on two targets (a primary, a bundle tag).
  expect_input_error(load(with("id: 4,", "id: 0,")),
                     {"network.yaml", "targets[1]", "tag id 0", "targets[0]"});
  expect_input_error(load(with("id: 4,", "id: 1,")),
                     {"network.yaml", "targets[1]", "tag id 1", "targets[0]"});
  expect_input_error(load(with("family: tag36h11, id: 4", "family: tag25h9, id: 4")),
                     {"network.yaml", "targets[1]", "family"});
  expect_input_error(load(with("targets:\n",
                               "target: {family: tag36h11, id: 9, size: 1}\n"
                               "targets:\n")),
                     {"network.yaml", "target", "either target or targets"});
  expect_input_error(load("fps: 30\ntargets: []\ncameras:\n  - {id: 1, p_wi: [0, 0, 0], "
                          "r_wi: [0, 0, 0]}\nedges: []\n"),
                     {"network.yaml", "targets", "at least one target"});
  expect_input_error(load(with("size: 0.1}", "size: -0.1}")),
                     {"network.yaml", "targets[1].size", "positive"});
}

// Synthesized: two bodies in one image, decided in one pass. Each observation holds its own
// target's tags only; a target out of the image is not_found while the other is detected.
TEST(Targets, FrontEndDecidesEveryTargetInOnePass) {
  const auto calib = testing::test_calibration(true);
  io::TargetConfig a, b;
  a.id = 0;
  a.size = 0.2;
  a.bundle.push_back(
      {1, 0.2, obs::make_pose(obs::Vec3(0.256066, 0, -0.106066), obs::Vec3(0, M_PI / 4, 0))});
  b.id = 4;
  b.size = 0.12;
  const obs::SE3 g_a = testing::facing_pose(2.2, -0.45, 0.05, obs::Vec3(0.1, 0.15, 0));
  const obs::SE3 g_b = testing::facing_pose(2.0, 0.5, -0.05, obs::Vec3(-0.05, 0.1, 0));
  std::vector<testing::SynthTag> tags{
      {0, 0.2, g_a, {}}, {1, 0.2, g_a * a.bundle[0].g_ot, {}}, {4, 0.12, g_b, {}}};
  testing::SynthSettings so;
  so.noise_sigma = 1.0;

  frontend::DetectorSettings ds;
  frontend::set_targets(ds, {a, b});
  EXPECT_EQ(ds.bundle_ids, (std::vector<int>{1, 4}));
  EXPECT_EQ(ds.tags_per_target, (std::vector<int>{2, 1}));
  frontend::FrontEnd fe(ds);
  ASSERT_EQ(fe.target_count(), 2u);
  frontend::FrameDetections all;
  const auto obs = fe.observe_targets(testing::render_tags(calib, tags, so), calib, &all);
  ASSERT_EQ(obs.size(), 2u);
  ASSERT_TRUE(obs[0].delta) << obs[0].reason;
  ASSERT_TRUE(obs[1].delta) << obs[1].reason;
  EXPECT_EQ(obs[0].slots, (std::vector<int>{0, 1}));
  EXPECT_EQ(obs[0].f_normalized.size(), 16);
  EXPECT_EQ(obs[1].slots, std::vector<int>{0});
  EXPECT_EQ(obs[1].tag_id, 4);
  EXPECT_EQ(obs[1].f_normalized.size(), 8);
  const auto truth_b = testing::project_corners(calib, g_b, 0.12);
  EXPECT_LT(testing::corner_rms(obs[1].corners_px, truth_b), 0.1);
  const auto truth_a = testing::project_corners(calib, g_a, 0.2);
  EXPECT_LT(testing::corner_rms(obs[0].corners_px, truth_a), 0.1);
  ASSERT_EQ(all.targets.size(), 2u);
  EXPECT_EQ(all.targets[1].first_tag, 2u);

  // Target B alone in the image: A not found with its own ids in the reason, B detected, the
  // same as a front end for B alone.
  const auto only_b = fe.observe_targets(testing::render_tags(calib, {tags[2]}, so), calib);
  EXPECT_FALSE(only_b[0].delta);
  EXPECT_NE(only_b[0].reason.find("ids 0, 1 not decoded"), std::string::npos) << only_b[0].reason;
  ASSERT_TRUE(only_b[1].delta) << only_b[1].reason;
  frontend::DetectorSettings ds_b;
  frontend::set_target(ds_b, b);
  frontend::FrontEnd fe_b(ds_b);
  const auto alone = fe_b.observe(testing::render_tags(calib, {tags[2]}, so), calib);
  ASSERT_TRUE(alone.delta);
  for (size_t k = 0; k < 4; ++k) EXPECT_EQ(alone.corners_px[k], only_b[1].corners_px[k]);
}

// Tracking with several targets: the window covers every target's tags; a target missing from
// the window sends the frame to a full-frame search, so both stay detected frame after frame.
TEST(Targets, TrackingKeepsEveryTarget) {
  const auto calib = testing::test_calibration(false);
  io::TargetConfig a, b;
  a.id = 0;
  a.size = 0.15;
  b.id = 4;
  b.size = 0.15;
  frontend::DetectorSettings ds;
  frontend::set_targets(ds, {a, b});
  frontend::FrontEnd fe(ds);
  frontend::TrackState track;
  for (int k = 0; k < 4; ++k) {
    const obs::SE3 g_a = testing::facing_pose(2.0, -0.5 + 0.02 * k, 0.0);
    // B appears in frame 2 only, far from A's window.
    std::vector<testing::SynthTag> tags{{0, 0.15, g_a, {}}};
    if (k >= 2) tags.push_back({4, 0.15, testing::facing_pose(2.0, 0.55, 0.1), {}});
    const auto o =
        fe.observe_targets(testing::render_tags(calib, tags, {}), calib, nullptr, &track);
    EXPECT_TRUE(o[0].delta) << "frame " << k;
    EXPECT_EQ(o[1].delta, k >= 2) << "frame " << k;
    EXPECT_EQ(track.last_all.size(), k >= 2 ? 2u : 1u);
  }
}

}  // namespace netvmo
