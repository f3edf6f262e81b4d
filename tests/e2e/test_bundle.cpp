// Tag bundles on images rendered at test time (datasets/tag_bundle.yaml: two tags on faces 45
// degrees apart): PnP on both tags' corners resolves the head-on view that one planar tag does
// not, a bundle stays detected with its primary tag hidden, and `netvmo run` converges to g*.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/render/renderer.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

namespace {
const fs::path kScenario = fs::path(NETVMO_SOURCE_DIR) / "datasets" / "tag_bundle.yaml";

double angle_deg(const obs::SE3& a, const obs::SE3& b) {
  return obs::log_so3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}

// The scenario's target as network.yaml has it (the bundle written by `netvmo render`).
io::TargetConfig bundle_target(const render::SceneDescription& scene) {
  return io::scene_network_config(scene, 1).target();
}

frontend::FrontEnd bundle_front_end(const io::TargetConfig& target) {
  frontend::DetectorSettings ds;
  frontend::set_target(ds, target);
  return frontend::FrontEnd(ds);
}
}  // namespace

// Head-on at 2 m (the setting of docs/frontend.md's 0.76 degrees for one 0.2 m tag): four cameras
// looking along the primary tag's normal from slightly different places, 2 noise realisations
// each, 4x4 supersampling. The same images give both estimates: PnP on the primary tag's 4
// corners and PnP on the 8 corners of both tags.
TEST(BundleOnRenderedImages, HeadOnBundleResolvesTheTiltOneTagCannot) {
  auto scene = io::load_render_scenario(kScenario);
  const auto target = bundle_target(scene);
  ASSERT_EQ(target.bundle.size(), 1u);
  const render::Vec3 centre = scene.target().motion.at(0.0).translation();
  const auto intrinsics = scene.cameras[0].intrinsics;
  scene.cameras.clear();
  scene.edges.clear();
  int id = 1;
  for (const auto& [dx, dz] : {std::pair{0.0, 0.0}, {-0.08, 0.05}, {0.06, -0.04}, {0.03, 0.08}}) {
    render::CameraSpec c;
    c.id = id++;
    c.intrinsics = intrinsics;
    c.g_wi_true =
        render::look_at(centre + render::Vec3(dx, -2.0, dz), centre, render::Vec3(0, 0, 1));
    c.g_wi_believed = c.g_wi_true;
    scene.cameras.push_back(c);
  }
  scene.imaging.spp = 16;
  render::Renderer r(scene);
  auto fe = bundle_front_end(target);
  const auto single_model = obs::FeatureModel::square(target.size);
  double sum_single = 0.0, sum_bundle = 0.0, max_bundle = 0.0, max_bundle_p = 0.0;
  int n = 0;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < r.camera_count(); ++i) {
      const auto calib = io::scene_calibration(scene.cameras[static_cast<size_t>(i)]);
      const auto o = fe.observe(r.render(i, k), calib);
      ASSERT_TRUE(o.delta) << "camera " << i + 1 << ": " << o.reason;
      ASSERT_EQ(o.slots, (std::vector<int>{0, 1})) << "camera " << i + 1;
      const obs::SE3 g_io = r.truth(i, k).g_io;
      const auto single = frontend::pnp_pose(o.f_normalized.head<8>(), single_model);
      const auto bundle =
          frontend::pnp_pose(o.f_normalized, frontend::observation_model(target, o));
      ASSERT_TRUE(single && bundle);
      const double es = angle_deg(single->g_io, g_io), eb = angle_deg(bundle->g_io, g_io);
      sum_single += es * es;
      sum_bundle += eb * eb;
      max_bundle = std::max(max_bundle, eb);
      max_bundle_p =
          std::max(max_bundle_p, (bundle->g_io.translation() - g_io.translation()).norm());
      ++n;
    }
  const double rms_single = std::sqrt(sum_single / n), rms_bundle = std::sqrt(sum_bundle / n);
  RecordProperty("rms_single_deg", std::to_string(rms_single));
  RecordProperty("rms_bundle_deg", std::to_string(rms_bundle));
  std::printf(
      "head-on PnP orientation error over %d images: one tag RMS %.3f deg, bundle RMS %.3f "
      "deg (max %.3f deg, position max %.2f mm)\n",
      n, rms_single, rms_bundle, max_bundle, 1e3 * max_bundle_p);
  // The second tag, seen 45 degrees off its normal, is what the 20-40 degree views of
  // FrontEndOnRenderedImages.PnpOfATwentyCentimetreTagAtTwoMetres resolve to 0.5 degrees; with
  // the depth spread of 8 non-coplanar corners the bundle must do better than a third of the
  // single head-on tag's error (measured: docs/images.md, "Tag bundles").
  EXPECT_LT(rms_bundle, rms_single / 3.0);
  EXPECT_LT(max_bundle, 0.25);
  EXPECT_LT(max_bundle_p, 0.005);
}

// A board in front of the primary tag hides it from the head-on camera; the second tag keeps
// the camera's delta = 1 and PnP on its 4 corners gives the body's pose.
TEST(BundleOnRenderedImages, BundleStaysDetectedWithItsPrimaryTagHidden) {
  const auto dir = test::scratch_dir("bundle_occluded");
  std::string yaml = test::slurp(kScenario);
  yaml +=
      "  - name: board\n"
      "    shapes:\n"
      "      - {type: box, size: [0.4, 0.01, 0.5], pose: {p: [-0.06, -0.1, 1.1]},\n"
      "         material: {pattern: solid, albedo: 0.5}}\n";
  std::ofstream(dir / "occluded.yaml") << yaml;
  auto scene = io::load_render_scenario(dir / "occluded.yaml");
  scene.cameras.resize(1);  // camera 1: head-on
  scene.edges.clear();
  const auto target = bundle_target(scene);
  render::Renderer r(scene);
  const auto truth = r.truth(0, 0);
  EXPECT_LT(truth.visible_fraction, 0.05) << "the board hides the primary tag";
  auto fe = bundle_front_end(target);
  frontend::FrameDetections all;
  const auto o = fe.observe(r.render(0, 0), io::scene_calibration(scene.cameras[0]), &all);
  ASSERT_TRUE(o.delta) << o.reason;
  EXPECT_EQ(o.slots, std::vector<int>{1});
  EXPECT_EQ(o.tag_id, 1);
  EXPECT_NE(all.tags[0].status, frontend::TargetStatus::detected);
  const auto pose = frontend::pnp_pose(o.f_normalized, frontend::observation_model(target, o));
  ASSERT_TRUE(pose);
  // One tag 45 degrees off its normal at 2.1 m: within 1 cm and 1 degree (the 20-40 degree views
  // of a single tag are within 5 mm and 0.5 degrees, FrontEndOnRenderedImages.*).
  const double ep = (pose->g_io.translation() - truth.g_io.translation()).norm();
  const double eR = angle_deg(pose->g_io, truth.g_io);
  std::printf("primary tag hidden: PnP on the second tag %.2f mm, %.3f deg from the truth\n",
              1e3 * ep, eR);
  EXPECT_LT(ep, 0.01);
  EXPECT_LT(eR, 1.0);
  fs::remove_all(dir);
}

// `netvmo render` writes the bundle into network.yaml; `netvmo run` with the jacobian error
// model (J stacked over every visible corner) brings every camera to g*, camera 3 seeing only
// the second tag; `netvmo detect` writes one row per tag of the body. 2 samples per pixel:
// at 1 the point-sampled corners leave the network ~0.8 degrees from g* (measured), at 2 and 4
// within 0.2 degrees.
TEST(BundleOnRenderedImages, RunOnABundleDatasetConvergesToGStar) {
  const auto dir = test::scratch_dir("bundle_run");
  const std::string ds = (dir / "ds").string(), out = (dir / "run").string();
  auto c = test::run_netvmo(
      "render " + kScenario.string() + " --out " + ds + " --frames 30 --spp 2 --quiet", dir, 120);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto net = io::load_network_config(fs::path(ds) / "network.yaml");
  ASSERT_EQ(net.target().bundle.size(), 1u);
  EXPECT_EQ(net.target().bundle[0].id, 1);
  c = test::run_netvmo("run " + ds + " --out " + out + " --error jacobian --no-overlays --no-plots",
                       dir, 120);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto s = nlohmann::json::parse(test::slurp(fs::path(out) / "summary.json"));
  ASSERT_EQ(s["cameras"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const auto& cam = s["cameras"][i];
    EXPECT_EQ(cam["seen_fraction"].get<double>(), 1.0) << "camera " << i + 1;
    const auto& e = cam["networked"]["vs_g_star"];
    EXPECT_LT(e["final_position_m"].get<double>(), 0.005) << "camera " << i + 1;
    EXPECT_LT(e["final_orientation_deg"].get<double>(), 0.5) << "camera " << i + 1;
  }
  c = test::run_netvmo("detect " + ds + " --out " + (dir / "det").string() + " --quiet", dir, 120);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto rows = io::read_detections_csv(dir / "det" / "detections.csv");
  ASSERT_EQ(rows.size(), 30u * 3u * 2u);
  // Camera 3 sees the primary tag 80 degrees off its normal: only the second tag is used.
  int cam3_primary = 0, cam3_second = 0;
  for (const auto& row : rows)
    if (row.camera == 3) (row.tag_id == 0 ? cam3_primary : cam3_second) += row.detected;
  EXPECT_EQ(cam3_primary, 0);
  EXPECT_EQ(cam3_second, 30);

  // The bundle's id made the primary's: one line naming network.yaml and the field, exit 1,
  // the earlier results left as they were.
  std::string yaml = test::slurp(fs::path(ds) / "network.yaml");
  const auto at = yaml.find("{id: 1,");
  ASSERT_NE(at, std::string::npos) << yaml;
  yaml.replace(at, 7, "{id: 0,");
  std::ofstream(fs::path(ds) / "network.yaml") << yaml;
  const std::string before = test::slurp(fs::path(out) / "summary.json");
  c = test::run_netvmo("run " + ds + " --out " + out + " --no-overlays --no-plots", dir, 60);
  EXPECT_EQ(c.code, 1);
  EXPECT_NE(c.err.find("network.yaml: target.bundle[0].id: tag id 0 listed twice"),
            std::string::npos)
      << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
  EXPECT_EQ(test::slurp(fs::path(out) / "summary.json"), before);
  fs::remove_all(dir);
}
