// Tag bundles (several tags on one body): network.yaml's target.bundle (reading, writing, bad
// input), the front end's decision over every tag of the body, and PnP on all their corners.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using test::expect_input_error;

const char* kBundleNetwork =
    "fps: 30\n"
    "target:\n"
    "  family: tag36h11\n"
    "  id: 3\n"
    "  size: 0.2\n"
    "  bundle:\n"
    "    - {id: 5, size: 0.15, p: [0.25, 0, -0.1], r: [0, 0.785398, 0]}\n"
    "    - {id: 7, size: 0.1, p: [-0.2, 0, 0], r: [0, 0, 0]}\n"
    "cameras:\n"
    "  - {id: 1, p_wi: [0, 0, 0], r_wi: [0, 0, 0]}\n"
    "edges: []\n";

fs::path write_network(const fs::path& dir, const std::string& text) {
  return test::write_text(dir / "network.yaml", text);
}

std::string with(const std::string& from, const std::string& to) {
  return test::replaced(kBundleNetwork, from, to);
}

// The wedge of datasets/tag_bundle.yaml: the primary tag and a second one turned 45 degrees
// about its vertical axis, hinged along the primary face's right edge.
io::TargetConfig wedge() {
  io::TargetConfig t;
  t.id = 0;
  t.size = 0.2;
  t.bundle.push_back(
      {1, 0.2, obs::make_pose(obs::Vec3(0.256066, 0, -0.106066), obs::Vec3(0, M_PI / 4, 0))});
  return t;
}
}  // namespace

TEST(Bundle, NetworkYamlReadsAndWritesTheBundle) {
  const auto dir = test::scratch_dir("bundle_ok");
  const auto n = io::load_network_config(write_network(dir, kBundleNetwork));
  ASSERT_EQ(n.target().bundle.size(), 2u);
  EXPECT_EQ(n.target().tag_count(), 3u);
  EXPECT_EQ(n.target().tag_id(0), 3);
  EXPECT_EQ(n.target().tag_id(2), 7);
  EXPECT_EQ(n.target().tag_size(1), 0.15);
  EXPECT_LT((n.target().tag_pose(1).translation() - obs::Vec3(0.25, 0, -0.1)).norm(), 1e-12);
  EXPECT_LT((obs::log_so3(n.target().tag_pose(1).linear()) - obs::Vec3(0, 0.785398, 0)).norm(),
            1e-12);
  EXPECT_TRUE(n.target().tag_pose(0).isApprox(obs::SE3::Identity()));
  // Written back, it reads the same.
  const auto back = io::load_network_config(write_network(dir, io::network_yaml(n)));
  ASSERT_EQ(back.target().bundle.size(), 2u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.target().tag_id(k), n.target().tag_id(k));
    EXPECT_EQ(back.target().tag_size(k), n.target().tag_size(k));
    EXPECT_TRUE(back.target().tag_pose(k).isApprox(n.target().tag_pose(k), 1e-11));
  }
  // Without a bundle nothing is written for it.
  io::NetworkConfig single = n;
  single.target().bundle.clear();
  EXPECT_EQ(io::network_yaml(single).find("bundle"), std::string::npos);
}

TEST(Bundle, BadBundlesGiveOneLineNamingFileRowAndField) {
  const auto dir = test::scratch_dir("bundle_bad");
  const auto load = [&](const std::string& text) {
    return [&dir, text] { io::load_network_config(write_network(dir, text)); };
  };
  // The primary's id listed again, a bundle id listed twice.
  expect_input_error(load(with("id: 5,", "id: 3,")),
                     {"network.yaml", "target.bundle[0].id", "listed twice", "primary"});
  expect_input_error(load(with("id: 7,", "id: 5,")),
                     {"network.yaml", "target.bundle[1].id", "tag id 5 listed twice"});
  expect_input_error(load(with("size: 0.1,", "size: 0,")),
                     {"network.yaml", "target.bundle[1].size", "positive"});
  expect_input_error(load(with("size: 0.1,", "size: -0.1,")),
                     {"network.yaml", "target.bundle[1].size", "positive"});
  // Coplanar with the primary, facing the same way, squares overlapping by 5 mm.
  expect_input_error(load(with("p: [-0.2, 0, 0]", "p: [-0.145, 0, 0]")),
                     {"network.yaml", "target.bundle[1]", "overlaps", "tag 3 (the primary)"});
  // Coincident centres (not coplanar: turned).
  expect_input_error(
      load(with("p: [-0.2, 0, 0], r: [0, 0, 0]", "p: [0.25, 0, -0.1], r: [1, 0, 0]")),
      {"network.yaml", "target.bundle[1]", "centre coincides", "bundle[0]"});
  expect_input_error(load(with("r: [0, 0.785398, 0]", "r: [0, 0.785398]")),
                     {"network.yaml", "target.bundle[0].r"});
  expect_input_error(load(with("size: 0.15,", "size: 0.15, family: tag36h11,")),
                     {"network.yaml", "target.bundle[0]", "family"});
}

TEST(Bundle, OverlapTestIsExact) {
  const obs::SE3 I = obs::SE3::Identity();
  const auto at = [](double x, double y, double z, obs::Vec3 r = obs::Vec3::Zero()) {
    return obs::make_pose(obs::Vec3(x, y, z), r);
  };
  // Side by side in one plane: touching edges pass, 1 mm of overlap fails.
  EXPECT_FALSE(io::tags_overlap(0.2, I, 0.2, at(0.2, 0, 0)));
  EXPECT_TRUE(io::tags_overlap(0.2, I, 0.2, at(0.199, 0, 0)));
  // A square turned 45 degrees in the plane: its corner reaches sqrt(2) x 0.05 from its centre.
  EXPECT_FALSE(io::tags_overlap(0.2, I, 0.1, at(0.1 + 0.0708, 0, 0, obs::Vec3(0, 0, M_PI / 4))));
  EXPECT_TRUE(io::tags_overlap(0.2, I, 0.1, at(0.1 + 0.0706, 0, 0, obs::Vec3(0, 0, M_PI / 4))));
  // Parallel planes 1 cm apart, or back to back: not the same printed surface.
  EXPECT_FALSE(io::tags_overlap(0.2, I, 0.2, at(0.05, 0, 0.01)));
  EXPECT_FALSE(io::tags_overlap(0.2, I, 0.2, at(0.05, 0, 0, obs::Vec3(M_PI, 0, 0))));
  // The wedge's faces.
  const auto w = wedge();
  EXPECT_FALSE(io::tags_overlap(w.size, I, w.bundle[0].size, w.bundle[0].g_ot));
}

TEST(Bundle, TagPointsAreEachTagsCornersInTheObjectFrame) {
  const auto w = wedge();
  const auto single = frontend::tag_points(w, {0});
  const auto square = obs::FeatureModel::square(0.2);
  ASSERT_EQ(single.points_o.size(), 4u);
  for (size_t k = 0; k < 4; ++k) EXPECT_TRUE(single.points_o[k].isApprox(square.points_o[k]));
  const auto both = frontend::tag_points(w, {0, 1});
  ASSERT_EQ(both.points_o.size(), 8u);
  for (size_t k = 0; k < 4; ++k)
    EXPECT_LT((both.points_o[4 + k] - w.bundle[0].g_ot * square.points_o[k]).norm(), 1e-15);
  // Corner 1 of the second tag (bottom right) lies 0.1 m along its face beyond its centre.
  EXPECT_LT((both.points_o[5] -
             obs::Vec3(0.256066 + 0.1 * std::sqrt(0.5), -0.1, -0.106066 - 0.1 * std::sqrt(0.5)))
                .norm(),
            1e-6);
}

// Synthesized: the wedge's two tags in one image. Both are accepted (corners in slot order),
// PnP on the 8 corners finds the pose; with the primary covered the second alone keeps delta.
TEST(Bundle, FrontEndUsesEveryAcceptedTagOfTheBody) {
  const auto calib = testing::test_calibration(true);
  const auto w = wedge();
  const obs::SE3 g_io = testing::facing_pose(1.6, -0.1, 0.02, obs::Vec3(0.1, 0.15, 0));
  std::vector<testing::SynthTag> tags{{0, 0.2, g_io, {}}, {1, 0.2, g_io * w.bundle[0].g_ot, {}}};
  testing::SynthSettings so;
  so.noise_sigma = 1.0;
  const cv::Mat img = testing::render_tags(calib, tags, so);

  frontend::DetectorSettings ds;
  frontend::set_target(ds, w);
  ASSERT_EQ(ds.bundle_ids, std::vector<int>{1});
  frontend::FrontEnd fe(ds);
  frontend::FrameDetections all;
  const auto o = fe.observe(img, calib, &all);
  ASSERT_TRUE(o.delta) << o.reason;
  EXPECT_EQ(o.slots, (std::vector<int>{0, 1}));
  ASSERT_EQ(all.tags.size(), 2u);
  EXPECT_EQ(all.tags[1].id, 1);
  EXPECT_EQ(all.tags[1].status, frontend::TargetStatus::detected);
  ASSERT_EQ(o.f_normalized.size(), 16);
  EXPECT_EQ(o.tag_id, 0);
  for (size_t t = 0; t < 2; ++t) {
    const auto truth = testing::project_corners(calib, tags[t].g_io, 0.2);
    EXPECT_LT(testing::corner_rms(o.tag_corners_px[t], truth), 0.1) << "tag " << t;
  }
  const auto pose = frontend::pnp_pose(o.f_normalized, frontend::observation_model(w, o));
  ASSERT_TRUE(pose);
  EXPECT_LT((pose->g_io.translation() - g_io.translation()).norm(), 0.002);
  EXPECT_LT(obs::log_so3(g_io.linear().transpose() * pose->g_io.linear()).norm(), 0.003);

  // The primary covered (an occluder over its whole quiet zone): the second tag alone.
  const auto c0 = testing::project_corners(calib, g_io, 0.3);
  cv::Rect box = cv::boundingRect(std::vector<cv::Point2f>(c0.begin(), c0.end()));
  so.occluders = {box};
  const auto o1 = fe.observe(testing::render_tags(calib, tags, so), calib, &all);
  ASSERT_TRUE(o1.delta) << o1.reason;
  EXPECT_EQ(o1.slots, std::vector<int>{1});
  EXPECT_EQ(o1.tag_id, 1);
  EXPECT_EQ(all.tags[0].status, frontend::TargetStatus::not_found);
  EXPECT_EQ(all.target_index, -1);
  const auto p1 = frontend::pnp_pose(o1.f_normalized, frontend::observation_model(w, o1));
  ASSERT_TRUE(p1);
  EXPECT_LT((p1->g_io.translation() - g_io.translation()).norm(), 0.01);

  // Neither tag in view: one reason naming both ids.
  const auto o2 = fe.observe(testing::render_tags(calib, {}, so), calib);
  EXPECT_FALSE(o2.delta);
  EXPECT_EQ(o2.status, frontend::TargetStatus::not_found);
  EXPECT_NE(o2.reason.find("ids 0, 1 not decoded"), std::string::npos) << o2.reason;
}

// Tracking covers every tag of the body: the window is around all accepted tags.
TEST(Bundle, TrackingKeepsBothTags) {
  const auto calib = testing::test_calibration(false);
  const auto w = wedge();
  const obs::SE3 g_io = testing::facing_pose(1.8, -0.15, 0.0, obs::Vec3(0.0, 0.3, 0));
  const cv::Mat img =
      testing::render_tags(calib, {{0, 0.2, g_io, {}}, {1, 0.2, g_io * w.bundle[0].g_ot, {}}});
  frontend::DetectorSettings ds;
  frontend::set_target(ds, w);
  frontend::FrontEnd fe(ds);
  frontend::TrackState track;
  const auto first = fe.observe(img, calib, nullptr, &track);
  ASSERT_EQ(first.slots, (std::vector<int>{0, 1}));
  EXPECT_EQ(track.last_all.size(), 2u);
  const auto second = fe.observe(img, calib, nullptr, &track);
  EXPECT_EQ(track.found_by, frontend::kSearchWindow);
  EXPECT_EQ(second.slots, (std::vector<int>{0, 1}));
  ASSERT_EQ(second.f_normalized.size(), 16);
  // The window's corners agree with the full frame's within 0.1 px (x 1/610 in normalized units;
  // libapriltag thresholds the window's tiles slightly differently).
  EXPECT_LT((second.f_normalized - first.f_normalized).cwiseAbs().maxCoeff(), 0.1 / 610);
}

TEST(Bundle, DetectorRefusesAnIdListedTwice) {
  frontend::DetectorSettings ds;
  ds.target_id = 2;
  ds.bundle_ids = {4, 2};
  expect_input_error([&] { frontend::TagDetector d(ds); }, {"tag id 2 listed twice"});
}

}  // namespace netvmo
