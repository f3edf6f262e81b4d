// The renderer's lens models (render::Intrinsics: radial-tangential, rational, fisheye) against
// OpenCV's own projection with the same coefficients; io::normalize_points inverts them and
// io::denormalize_points repeats them on the calibration `netvmo render` writes, through the
// OpenCV and ROS calibration files; a fisheye scenario renders and its truth corners are where
// the tag is imaged.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <random>
#include <tuple>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using netvmo::render::Intrinsics;

namespace {

Intrinsics lens(Intrinsics::Lens model) {
  Intrinsics k;
  k.fx = 420;
  k.fy = 415;
  k.cx = 322.5;
  k.cy = 236.0;
  k.lens = model;
  if (model == Intrinsics::Lens::Fisheye)
    k.dist = {0.08, -0.03, 0.012, -0.002, 0, 0, 0, 0};
  else if (model == Intrinsics::Lens::Rational)
    k.dist = {0.9, 0.25, 0.001, -0.0015, 0.01, 1.2, 0.45, 0.03};
  else
    k.dist = {-0.28, 0.09, 0.001, -0.0012, -0.01, 0, 0, 0};
  return k;
}

// Camera-frame points spread over a 100 degree field of view, 0.5-5 m away.
std::vector<cv::Point3d> points() {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> a(-0.85, 0.85), z(0.5, 5);
  std::vector<cv::Point3d> out;
  for (int i = 0; i < 200; ++i) {
    const double d = z(rng);
    out.emplace_back(a(rng) * d, 0.8 * a(rng) * d, d);
  }
  return out;
}

netvmo::io::Calibration calibration(const Intrinsics& k) {
  netvmo::render::CameraSpec c;
  c.intrinsics = k;
  return netvmo::io::scene_calibration(c);
}

void check_model(Intrinsics::Lens model) {
  const Intrinsics k = lens(model);
  const netvmo::io::Calibration calib = calibration(k);
  EXPECT_EQ(calib.fisheye, model == Intrinsics::Lens::Fisheye);
  const auto P = points();
  std::vector<cv::Point2d> cv_px;
  if (model == Intrinsics::Lens::Fisheye)
    cv::fisheye::projectPoints(P, cv_px, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                               calib.distortion());
  else
    cv::projectPoints(P, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                      calib.distortion(), cv_px);
  std::vector<cv::Point2d> px, xy;
  for (size_t i = 0; i < P.size(); ++i) {
    const auto uv = k.project(netvmo::render::Vec3(P[i].x, P[i].y, P[i].z));
    ASSERT_TRUE(uv);
    EXPECT_NEAR(uv->x(), cv_px[i].x, 1e-8) << i;
    EXPECT_NEAR(uv->y(), cv_px[i].y, 1e-8) << i;
    px.emplace_back(uv->x(), uv->y());
    xy.emplace_back(P[i].x / P[i].z, P[i].y / P[i].z);
    const auto back = k.unproject(*uv);
    ASSERT_TRUE(back) << i;
    EXPECT_NEAR(back->x(), xy.back().x, 1e-9) << i;
  }
  // The front end's conversions, through the files `netvmo render` writes and ROS's.
  const fs::path dir = netvmo::test::scratch_dir("lens_models");
  netvmo::io::save_calibration_opencv(dir / "cv.yaml", calib);
  netvmo::io::save_calibration_ros(dir / "ros.yaml", calib, "cam_1");
  for (const auto& c : {netvmo::io::load_calibration_opencv(dir / "cv.yaml"),
                        netvmo::io::load_calibration_ros(dir / "ros.yaml")}) {
    EXPECT_EQ(c.fisheye, calib.fisheye);
    const auto n = netvmo::io::normalize_points(px, c);
    const auto d = netvmo::io::denormalize_points(xy, c);
    for (size_t i = 0; i < px.size(); ++i) {
      EXPECT_NEAR(n[i].x, xy[i].x, 1e-9) << i;
      EXPECT_NEAR(n[i].y, xy[i].y, 1e-9) << i;
      EXPECT_NEAR(d[i].x, px[i].x, 1e-7) << i;
      EXPECT_NEAR(d[i].y, px[i].y, 1e-7) << i;
    }
  }
}

TEST(LensModels, RadTanEqualsProjectPoints) {
  check_model(Intrinsics::Lens::RadTan);
}
TEST(LensModels, RationalEqualsProjectPoints) {
  check_model(Intrinsics::Lens::Rational);
}
TEST(LensModels, FisheyeEqualsFisheyeProjectPoints) {
  check_model(Intrinsics::Lens::Fisheye);
}

TEST(LensModels, UnsupportedLensModelNamesFileAndKey) {
  const fs::path dir = netvmo::test::scratch_dir("lens_models");
  netvmo::io::save_calibration_opencv(dir / "fish.yaml",
                                      calibration(lens(Intrinsics::Lens::Fisheye)));
  std::ifstream in(dir / "fish.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [from, to, needle] :
       {std::tuple<std::string, std::string, std::string>{"fisheye", "kannala", "lens_model"},
        {"cols: 4", "cols: 5", "distortion_coefficients"}}) {
    // cols: 4 appears first in distortion_coefficients (the camera matrix has cols: 3).
    std::string bad = text;
    bad.replace(bad.find(from), from.size(), to);
    if (from == "cols: 4")  // a fifth coefficient
      bad.replace(bad.find("data: [ ", bad.find("distortion_coefficients")), 8, "data: [ 0., ");
    std::ofstream(dir / "bad.yaml") << bad;
    try {
      netvmo::io::load_calibration_opencv(dir / "bad.yaml");
      ADD_FAILURE() << "accepted\n" << bad;
    } catch (const netvmo::InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find((dir / "bad.yaml").string() + ": " + needle), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  }
}

TEST(LensModels, FisheyeImageShowsTheTagAtItsTruthCorners) {
  netvmo::render::SceneDescription s;
  netvmo::render::CameraSpec cam;
  cam.intrinsics = lens(Intrinsics::Lens::Fisheye);
  cam.intrinsics.width = 320;
  cam.intrinsics.height = 240;
  cam.intrinsics.cx = 159.5;
  cam.intrinsics.cy = 119.5;
  cam.intrinsics.fx = cam.intrinsics.fy = 200;
  s.cameras.push_back(cam);
  // A tag off-axis, 1 m away, facing the camera (flipped about x).
  s.target().motion = netvmo::render::Trajectory::fixed(netvmo::render::make_pose(
      netvmo::render::Vec3(0.45, 0.25, 1.0), netvmo::render::Vec3(M_PI, 0, 0)));
  s.imaging.noise = false;
  s.imaging.spp = 4;
  netvmo::render::Renderer r(s);
  const cv::Mat img = r.render(0, 0);
  const auto t = r.truth(0, 0);
  ASSERT_TRUE(t.in_fov);
  // Inside the black square, just in from each corner towards the centre: dark; just out: light.
  cv::Point2d c(0, 0);
  for (const auto& k : t.corners) c += cv::Point2d(k->x(), k->y()) * 0.25;
  for (const auto& k : t.corners) {
    const cv::Point2d p(k->x(), k->y()), in = p + 0.15 * (c - p), out = p - 0.15 * (c - p);
    // Ambient light only: paper 0.85 * 0.3 * 255 = 65 DN, ink 4 DN.
    EXPECT_LT(img.at<std::uint8_t>(cvRound(in.y), cvRound(in.x)), 20) << p;
    EXPECT_GT(img.at<std::uint8_t>(cvRound(out.y), cvRound(out.x)), 50) << p;
  }
}

}  // namespace
