// The render scenario loader: the shipped scenarios load; strict reading names the file and the
// key path for an unknown key, a non-number and a missing value.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

// The scenario, kept as a data file next to this test.
const std::string kMinimal =
    netvmo::test::slurp(fs::path(NETVMO_SOURCE_DIR) / "tests/pipeline/data/minimal_scenario.yaml");

fs::path write_scenario(const std::string& name, const std::string& text) {
  static const fs::path dir = netvmo::test::scratch_dir("scenario_yaml");
  const fs::path f = dir / name;
  std::ofstream(f) << text;
  return f;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

// Loads and returns the InputError message ("" if it loaded).
std::string load_error(const fs::path& f) {
  try {
    netvmo::io::load_render_scenario(f);
  } catch (const netvmo::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RenderScenario, MinimalLoads) {
  const auto s = netvmo::io::load_render_scenario(write_scenario("ok.yaml", kMinimal));
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.cameras[0].id, 4);
  EXPECT_EQ(s.cameras[1].id, 9);
  EXPECT_DOUBLE_EQ(s.cameras[0].intrinsics.cx, 39.5);  // default: image centre
  EXPECT_DOUBLE_EQ(s.cameras[1].intrinsics.dist[0], -0.05);
  EXPECT_NEAR((s.cameras[0].g_wi_believed.translation() - s.cameras[0].g_wi_true.translation()).x(),
              0.01, 1e-12);
  EXPECT_EQ(s.target().tag.id, 2);
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.imaging.spp, 1);
  EXPECT_EQ(s.imaging.seed, 5u);
  EXPECT_EQ(s.imaging.sampling, netvmo::render::Imaging::Sampling::Grid);
  ASSERT_EQ(s.edges.size(), 1u);
  EXPECT_EQ(s.target().motion.kind, netvmo::render::Trajectory::Kind::Twist);
}

TEST(RenderScenario, ShippedScenariosLoad) {
  for (const char* name : {"paper5_render.yaml", "moving_target.yaml",
                           "paper5_render_realistic.yaml", "moving_target_realistic.yaml"}) {
    const auto s =
        netvmo::io::load_render_scenario(fs::path(NETVMO_SOURCE_DIR) / "datasets" / name);
    EXPECT_EQ(s.cameras.size(), 5u) << name;
    EXPECT_EQ(s.edges.size(), 6u) << name;
  }
}

TEST(RenderScenario, UnknownKeyNamesFileAndPath) {
  const auto f = write_scenario("unknown.yaml",
                                replaced(kMinimal, "fx: 70, fy: 70}", "fx: 70, fy: 70, fz: 1}"));
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].intrinsics.fz"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown key"), std::string::npos) << msg;
}

TEST(RenderScenario, UnknownTopLevelKey) {
  const auto f = write_scenario("unknown_top.yaml", kMinimal + "lightz: []\n");
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find("lightz: unknown key"), std::string::npos) << msg;
}

TEST(RenderScenario, NonNumberNamesFileAndPath) {
  const auto f = write_scenario("nan.yaml", replaced(kMinimal, "size: 0.15", "size: big"));
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("target.tag.size"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected a number"), std::string::npos) << msg;
}

TEST(RenderScenario, MissingValueNamesPath) {
  const auto f = write_scenario("missing.yaml", replaced(kMinimal, "fps: 30\n", ""));
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find("fps: missing value"), std::string::npos) << msg;
}

TEST(RenderScenario, ObjShapeIsReadRelativeToTheScenario) {
  const auto dir =
      write_scenario("mesh.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").parent_path();
  const std::string with_obj =
      replaced(kMinimal, "{type: plane, size: [6, 6],", "{type: obj, file: mesh.obj, scale: 2.0,");
  const auto s = netvmo::io::load_render_scenario(write_scenario("obj.yaml", with_obj));
  ASSERT_EQ(s.occluders.size(), 1u);
  const auto& m = s.occluders[0].shapes[0].mesh;
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_FLOAT_EQ(m.vertices[2].x(), 2.0f);
  const std::string msg =
      load_error(write_scenario("obj_missing.yaml", replaced(with_obj, "mesh.obj", "nope.obj")));
  EXPECT_NE(msg.find("occluders[0].shapes[0].file: cannot read OBJ file"), std::string::npos)
      << msg;
  (void)dir;
}

// A camera's `motion` (the body motion syntax) drives its true pose; its believed pose keeps the
// t = 0 mis-registration and drifts with `believed_drift`.
TEST(RenderScenario, MovingCameras) {
  const auto f = write_scenario(
      "moving_cam.yaml",
      replaced(kMinimal, "pose: {eye: [0, -1.5, 1.0], look_at: [0, 0, 1.0]}",
               "motion: {type: twist, pose: {eye: [0, -1.5, 1.0], look_at: [0, 0, 1.0]}, "
               "v: [0.2, 0, 0], w: [0, 0.1, 0]}\n    believed_drift: {dp: [0.01, 0, 0]}"));
  const auto s = netvmo::io::load_render_scenario(f);
  const auto& c = s.cameras[0];
  ASSERT_TRUE(c.motion.has_value());
  EXPECT_TRUE(c.moving());
  EXPECT_FALSE(s.cameras[1].moving());
  const auto V = (netvmo::render::Vec6() << 0.2, 0, 0, 0, 0.1, 0).finished();
  EXPECT_TRUE(c.true_pose(2.0).isApprox(c.g_wi_true * netvmo::render::exp_se3(2.0 * V), 1e-12));
  // Believed = Delta(t) true(t), Delta(t) = [I, t dp] Delta(0), Delta(0) = believed(0) true(0)^-1.
  const auto delta0 = c.g_wi_believed * c.g_wi_true.inverse();
  auto drift = netvmo::render::Pose::Identity();
  drift.translation() = netvmo::render::Vec3(0.02, 0, 0);
  EXPECT_TRUE(c.believed_pose(2.0).isApprox(drift * delta0 * c.true_pose(2.0), 1e-12));
  EXPECT_TRUE(c.believed_pose(0.0).isApprox(c.g_wi_believed, 1e-12));

  const auto moving = netvmo::io::load_render_scenario(fs::path(NETVMO_SOURCE_DIR) / "datasets" /
                                                       "moving_cameras.yaml");
  EXPECT_EQ(moving.cameras.size(), 4u);
  for (const auto& cam : moving.cameras) EXPECT_TRUE(cam.moving()) << cam.id;

  const std::string both = load_error(write_scenario(
      "pose_and_motion.yaml",
      replaced(kMinimal, "look_at: [0, 0, 1.0]}\n",
               "look_at: [0, 0, 1.0]}\n    motion: {type: static, pose: {p: [0, 0, 0]}}\n")));
  EXPECT_NE(both.find("cameras[0].motion: give either pose or motion"), std::string::npos) << both;
  const std::string drift_key = load_error(write_scenario(
      "drift_key.yaml", replaced(kMinimal, "look_at: [0, 0, 1.0]}\n",
                                 "look_at: [0, 0, 1.0]}\n    believed_drift: {dv: [0, 0, 1]}\n")));
  EXPECT_NE(drift_key.find("cameras[0].believed_drift.dv"), std::string::npos) << drift_key;
  const std::string keys = load_error(write_scenario(
      "cam_keys.yaml", replaced(kMinimal, "pose: {eye: [0, -1.5, 1.0], look_at: [0, 0, 1.0]}",
                                "motion: {type: keyframes, keyframes: [{t: 1, pose: {p: [0, 0, "
                                "0]}}, {t: 0.5, pose: {p: [1, 0, 0]}}]}")));
  EXPECT_NE(keys.find("cameras[0].motion.keyframes[1].t"), std::string::npos) << keys;
}

TEST(RenderScenario, BadValuesAreRejected) {
  EXPECT_NE(load_error(write_scenario("edge.yaml", replaced(kMinimal, "[[4, 9]]", "[[4, 5]]")))
                .find("edges[0]"),
            std::string::npos);
  EXPECT_NE(load_error(write_scenario("fam.yaml", replaced(kMinimal, "tag36h11", "tag99h1")))
                .find("unknown tag family"),
            std::string::npos);
  EXPECT_NE(load_error(write_scenario("id.yaml", replaced(kMinimal, "id: 9", "id: 4")))
                .find("duplicate camera id"),
            std::string::npos);
  EXPECT_NE(
      load_error(write_scenario("shape.yaml", replaced(kMinimal, "type: box", "type: sphere")))
          .find("target.shapes[0].type"),
      std::string::npos);
  EXPECT_NE(load_error(fs::path(NETVMO_BINARY_DIR) / "no_such_file.yaml").find("file not found"),
            std::string::npos);
}

// The realistic camera model's keys (docs/realistic_camera.md): out of their physical range each
// gives one line naming the file and the key.
void expect_rejected(const std::string& name, const std::string& from, const std::string& to,
                     const std::string& key) {
  const auto f = write_scenario(name, replaced(kMinimal, from, to));
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find(key), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(RenderScenario, PrintKeys) {
  const auto tag = [](const std::string& print) { return "size: 0.15, print: " + print + "}"; };
  auto s = netvmo::io::load_render_scenario(write_scenario(
      "print.yaml",
      replaced(kMinimal, "size: 0.15}", tag("{ink_spread: -0.1, gloss: 0.3, bend: -4}"))));
  EXPECT_DOUBLE_EQ(s.target().tag.print.ink_spread, -0.1);
  EXPECT_DOUBLE_EQ(s.target().tag.print.gloss, 0.3);
  EXPECT_DOUBLE_EQ(s.target().tag.print.bend, -4);
  EXPECT_TRUE(s.target().tag.print.even_border());
  s = netvmo::io::load_render_scenario(write_scenario(
      "border.yaml", replaced(kMinimal, "size: 0.15}", tag("{border_width: [1.2, 1, 0.75, 1]}"))));
  EXPECT_TRUE((s.target().tag.print.border_width == std::array<double, 4>{1.2, 1, 0.75, 1}));
  s = netvmo::io::load_render_scenario(
      write_scenario("print_preset.yaml", replaced(kMinimal, "size: 0.15}", tag("realistic"))));
  EXPECT_TRUE(s.target().tag.print == netvmo::render::PrintModel::realistic());
  s = netvmo::io::load_render_scenario(write_scenario(
      "print_scene.yaml",
      replaced(kMinimal, "{spp: 1, seed: 5}", "{spp: 1, seed: 5, camera_model: realistic}")));
  EXPECT_TRUE(s.target().tag.print == netvmo::render::PrintModel::realistic());
  expect_rejected("ink.yaml", "size: 0.15}", tag("{ink_spread: 0.6}"),
                  "target.tag.print.ink_spread");
  expect_rejected("gloss.yaml", "size: 0.15}", tag("{gloss: -1}"), "target.tag.print.gloss");
  expect_rejected("shiny.yaml", "size: 0.15}", tag("{shininess: 0}"), "target.tag.print.shininess");
  expect_rejected("preset.yaml", "size: 0.15}", tag("glossy"), "target.tag.print");
  expect_rejected("border.yaml", "size: 0.15}", tag("{border_width: [1, 1, 0.4, 1]}"),
                  "target.tag.print.border_width");
  expect_rejected("border3.yaml", "size: 0.15}", tag("{border_width: [1, 1, 1]}"),
                  "target.tag.print.border_width");
  // A 0.15 m tag36h11 is printed 0.225 m wide: its ends 1.5 rad round at a bend of 13.3 / m.
  expect_rejected("bend.yaml", "size: 0.15}", tag("{bend: 13.4}"), "target.tag.print.bend");
  EXPECT_NO_THROW(netvmo::io::load_render_scenario(
      write_scenario("bend_max.yaml", replaced(kMinimal, "size: 0.15}", tag("{bend: -13.3}")))));
  expect_rejected("model.yaml", "{spp: 1, seed: 5}", "{spp: 1, camera_model: fancy}",
                  "imaging.camera_model");
  s = netvmo::io::load_render_scenario(write_scenario(
      "jittered.yaml",
      replaced(kMinimal, "{spp: 1, seed: 5}", "{spp: 1, seed: 5, sampling: jittered}")));
  EXPECT_EQ(s.imaging.sampling, netvmo::render::Imaging::Sampling::Jittered);
  expect_rejected("sampling.yaml", "{spp: 1, seed: 5}", "{spp: 1, sampling: random}",
                  "imaging.sampling");
}

TEST(RenderScenario, SensorKeys) {
  const std::string cam = "fx: 70, fy: 70}";
  const auto with = [&](const std::string& sensor) { return cam + "\n    sensor: " + sensor; };
  auto s = netvmo::io::load_render_scenario(write_scenario(
      "sensor.yaml",
      replaced(kMinimal, cam,
               with("{gain: 2, gamma: 2.4, full_well: 200, bloom: 0.5, vignetting: cos4, "
                    "psf_sigma: 0.7, jpeg_quality: 75, sharpen_amount: 1.5, sharpen_sigma: 0.8, "
                    "exposure_time: 0.01, line_delay: 3e-5, f_number: 2, focus_distance: 1.5, "
                    "focal_length_mm: 8}"))));
  const auto& sm = s.cameras[0].sensor;
  EXPECT_DOUBLE_EQ(sm.gain, 2);
  EXPECT_EQ(sm.tone, netvmo::render::SensorModel::Tone::Gamma);
  EXPECT_DOUBLE_EQ(sm.gamma, 2.4);
  EXPECT_EQ(sm.vignetting, netvmo::render::SensorModel::Vignetting::Cos4);
  EXPECT_EQ(sm.jpeg_quality, 75);
  EXPECT_DOUBLE_EQ(sm.sharpen_amount, 1.5);
  EXPECT_DOUBLE_EQ(sm.sharpen_sigma, 0.8);
  EXPECT_DOUBLE_EQ(sm.line_delay, 3e-5);
  EXPECT_DOUBLE_EQ(sm.focal_length_m(70), 8e-3);
  EXPECT_FALSE(s.cameras[1].sensor.image_effects());
  s = netvmo::io::load_render_scenario(write_scenario(
      "sensor_scene.yaml",
      replaced(kMinimal, "{spp: 1, seed: 5}", "{spp: 1, seed: 5, camera_model: realistic}")));
  EXPECT_EQ(s.cameras[1].sensor.jpeg_quality,
            netvmo::render::SensorModel::realistic().jpeg_quality);
  const std::string k = "cameras[0].sensor.";
  expect_rejected("s1.yaml", cam, with("{exposure_time: -0.001}"), k + "exposure_time");
  expect_rejected("s2.yaml", cam, with("{f_number: 0.3, focal_length_mm: 6}"), k + "f_number");
  expect_rejected("s3.yaml", cam, with("{jpeg_quality: 101}"), k + "jpeg_quality");
  expect_rejected("s4.yaml", cam, with("{gamma: 0}"), k + "gamma");
  expect_rejected("s5.yaml", cam, with("{gain: -1}"), k + "gain");
  expect_rejected("s6.yaml", cam, with("{bloom: 2}"), k + "bloom");
  expect_rejected("s7.yaml", cam, with("{psf_sigma: -1}"), k + "psf_sigma");
  expect_rejected("s8.yaml", cam, with("{tone: log}"), k + "tone");
  expect_rejected("s9.yaml", cam, with("{vignetting: cos3}"), k + "vignetting");
  expect_rejected("s10.yaml", cam, with("{f_number: 2}"), "cameras[0].sensor");
  expect_rejected("s11.yaml", cam, with("{focus_distance: -2}"), k + "focus_distance");
  expect_rejected("s12.yaml", cam, with("{line_delay: 1}"), k + "line_delay");
  expect_rejected("s13.yaml", cam, with("{shutter: 1}"), k + "shutter");
  expect_rejected("s14.yaml", cam, with("fancy"), "cameras[0].sensor");
  expect_rejected("s15.yaml", cam, with("{sharpen_amount: -1}"), k + "sharpen_amount");
  expect_rejected("s16.yaml", cam, with("{sharpen_amount: 1, sharpen_sigma: 0}"),
                  k + "sharpen_sigma");
}

TEST(RenderScenario, LensKeys) {
  const std::string cam = "fx: 70, fy: 70}";
  auto s = netvmo::io::load_render_scenario(write_scenario(
      "fisheye.yaml",
      replaced(kMinimal, cam, "fx: 70, fy: 70, lens: fisheye, distortion: [0.1, 0, 0, 0]}")));
  EXPECT_EQ(s.cameras[0].intrinsics.lens, netvmo::render::Intrinsics::Lens::Fisheye);
  EXPECT_TRUE(netvmo::io::scene_calibration(s.cameras[0]).fisheye);
  s = netvmo::io::load_render_scenario(write_scenario(
      "rational.yaml", replaced(kMinimal, cam,
                                "fx: 70, fy: 70, lens: rational, distortion: [0.1, 0, 0, 0, 0, "
                                "0.2, 0, 0]}")));
  EXPECT_DOUBLE_EQ(netvmo::io::scene_calibration(s.cameras[0]).rational[0], 0.2);
  expect_rejected("lens.yaml", cam, "fx: 70, fy: 70, lens: kannala}", "cameras[0].intrinsics.lens");
  expect_rejected("lens_n.yaml", cam, "fx: 70, fy: 70, lens: fisheye, distortion: [0, 0, 0, 0, 0]}",
                  "cameras[0].intrinsics.distortion");
}

}  // namespace
