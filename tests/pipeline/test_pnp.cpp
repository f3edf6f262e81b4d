// ViSP PnP from detected corners of synthesized frames: accuracy against the true g_io and the
// frame convention (tag z out of the printed face).
#include <gtest/gtest.h>

#include <cstdio>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "synth.hpp"

namespace netvmo {
namespace {
using namespace io;
using namespace frontend;
using testing::facing_pose;

double angle_deg(const obs::SE3& a, const obs::SE3& b) {
  return obs::log_so3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}

// Exact normalized features -> exact pose (no image involved), including the planar ambiguity
// cases at strong tilt.
TEST(Pnp, ExactFeaturesGiveExactPose) {
  const auto model = obs::FeatureModel::square(0.2);
  for (const auto& g : {facing_pose(2.0, 0.1, -0.2, {0.3, 0.2, 0.5}),
                        facing_pose(1.0, -0.3, 0.1, {-0.8, 0.4, -2.0}),
                        facing_pose(4.0, 0.5, 0.5, {0.0, 1.0, 3.0})}) {
    const auto r = pnp_pose(obs::project(g, model), model);
    ASSERT_TRUE(r.has_value());
    EXPECT_LT((r->g_io.translation() - g.translation()).norm(), 1e-6);
    EXPECT_LT(angle_deg(r->g_io, g), 1e-4);
    EXPECT_LT(r->residual, 1e-8);
  }
}

// A tag facing the camera: its z axis points toward -z_camera, its y axis up (-y_camera).
TEST(Pnp, ConventionTagFacingCamera) {
  const auto calib = testing::test_calibration();
  const obs::SE3 g = facing_pose(2.0);
  FrontEnd fe;
  const auto o = fe.observe(testing::render_tags(calib, {{0, 0.2, g, {}}}), calib);
  ASSERT_TRUE(o.delta);
  const auto r = pnp_pose(o.f_normalized, obs::FeatureModel::square(0.2));
  ASSERT_TRUE(r.has_value());
  const obs::Mat3 R = r->g_io.linear();
  EXPECT_LT(R.col(2).dot(obs::Vec3(0, 0, 1)), -0.99);  // tag z toward the camera
  EXPECT_LT(R.col(1).dot(obs::Vec3(0, 1, 0)), -0.99);  // tag y up in the image
  EXPECT_GT(R.col(0).dot(obs::Vec3(1, 0, 0)), 0.99);   // tag x right
  EXPECT_NEAR(r->g_io.translation().z(), 2.0, 0.005);
}

// A 0.2 m tag at 2 m: within 5 mm and 0.5 deg of the true g_io, several poses, with and
// without lens distortion, clean and with noise sigma 2.
TEST(Pnp, RenderedFramesWithin5mmAndHalfDegree) {
  const auto model = obs::FeatureModel::square(0.2);
  for (bool distortion : {false, true}) {
    const auto calib = testing::test_calibration(distortion);
    FrontEnd fe;
    double worst_mm = 0, worst_deg = 0;
    std::uint64_t seed = 3;
    for (const auto& g : {facing_pose(2.0, 0.0, 0.0, {0.2, -0.1, 0.3}),
                          facing_pose(2.0, 0.5, 0.3, {-0.35, 0.25, 1.4}),
                          facing_pose(2.0, -0.6, -0.4, {0.4, 0.3, -2.2}),
                          facing_pose(2.0, 0.2, -0.5, {0.0, -0.5, 0.7})})
      for (double noise : {0.0, 2.0}) {
        testing::SynthSettings opt;
        opt.noise_sigma = noise;
        opt.seed = seed++;
        const auto o = fe.observe(testing::render_tags(calib, {{0, 0.2, g, {}}}, opt), calib);
        ASSERT_TRUE(o.delta);
        const auto r = pnp_pose(o.f_normalized, model);
        ASSERT_TRUE(r.has_value());
        const double mm = 1000 * (r->g_io.translation() - g.translation()).norm();
        const double deg = angle_deg(r->g_io, g);
        worst_mm = std::max(worst_mm, mm);
        worst_deg = std::max(worst_deg, deg);
        EXPECT_LT(mm, 5.0) << "distortion " << distortion << " noise " << noise;
        EXPECT_LT(deg, 0.5) << "distortion " << distortion << " noise " << noise;
      }
    std::printf("PnP at 2 m (%s distortion): worst %.2f mm, %.3f deg\n",
                distortion ? "with" : "without", worst_mm, worst_deg);
  }
}

TEST(Pnp, ErrorModelIsERofRelativePose) {
  const obs::SE3 g_bar = facing_pose(2.0, 0.1, 0.0, {0.1, 0.0, 0.0});
  const obs::SE3 g_pnp = facing_pose(2.1, 0.1, 0.05, {0.1, 0.05, 0.0});
  const obs::Vec6 e = pnp_error(g_bar, g_pnp);
  EXPECT_TRUE(e.isApprox(obs::E_R(g_bar.inverse() * g_pnp)));
  EXPECT_LT(pnp_error(g_bar, g_bar).norm(), 1e-12);
}

}  // namespace
}  // namespace netvmo
