// The realistic camera model (docs/realistic_camera.md), each effect against a closed form on a
// fronto-parallel tag: ink spread moves the imaged black/white edge by ink_spread * cell px, a
// glossy print adds its Blinn-Phong term.
#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

// A 0.2 m tag36h11 (8 cells at the border, 0.025 m each) 1 m in front of a 600 px camera: a cell
// is 15 px and the black square's left edge is at u = 319.5 - 60 = 259.5.
constexpr double kCellPx = 15.0, kLeftEdge = 259.5;

SceneDescription fronto_scene(int spp = 16) {
  return testing::single_tag_scene(testing::facing_pose(Vec3(0, 0, 1), Vec3::Zero()), spp);
}

// Mean of rows [r0, r1) of column u.
double column_mean(const cv::Mat& img, int u, int r0, int r1) {
  double s = 0;
  for (int r = r0; r < r1; ++r) s += img.at<std::uint8_t>(r, u);
  return s / (r1 - r0);
}

// Where the mean of rows [r0, r1) first crosses half-way from its value at u0 to its value at u1
// (u0 < u1), by linear interpolation between pixel centres.
double edge_position(const cv::Mat& img, int u0, int u1, int r0, int r1) {
  const double a = column_mean(img, u0, r0, r1), b = column_mean(img, u1, r0, r1);
  const double level = 0.5 * (a + b);
  for (int u = u0; u < u1; ++u) {
    const double p = column_mean(img, u, r0, r1), q = column_mean(img, u + 1, r0, r1);
    if ((p - level) * (q - level) <= 0 && p != q) return u + (p - level) / (p - q);
  }
  return std::nan("");
}

// The black square's left edge, measured over rows well inside the tag.
double left_edge(const cv::Mat& img) {
  return edge_position(img, int(kLeftEdge) - 10, int(kLeftEdge) + 10, 200, 280);
}

TEST(RealisticPrint, CleanEdgeIsWhereTheGeometrySaysIt) {
  Renderer r(fronto_scene());
  EXPECT_NEAR(left_edge(r.render(0, 0)), kLeftEdge, 0.05);
}

TEST(RealisticPrint, InkSpreadMovesTheEdgeByItsFractionOfACell) {
  for (double f : {0.2, -0.2, 0.45}) {
    SceneDescription s = fronto_scene();
    s.target().tag.print.ink_spread = f;
    Renderer r(s);
    // 4 x 4 samples per pixel: an edge is located to within 1/8 px.
    EXPECT_NEAR(left_edge(r.render(0, 0)), kLeftEdge - f * kCellPx, 0.13) << "ink_spread " << f;
  }
}

TEST(RealisticPrint, InkSpreadOutOfRangeIsRefused) {
  SceneDescription s = fronto_scene();
  s.target().tag.print.ink_spread = 0.6;
  EXPECT_THROW(Renderer r(s), std::invalid_argument);
}

TEST(RealisticPrint, GlossAddsTheBlinnPhongTerm) {
  SceneDescription s = fronto_scene();
  s.target().tag.print.gloss = 0.2;
  s.target().tag.print.shininess = 1;
  Renderer clean(fronto_scene()), glossy(s);
  // Quiet-zone pixel at u = 252 (x = -0.1125 m on the tag): the light travels along +z, the
  // face's normal is -z, the viewer is at the origin.
  const int u = 252, v = 239;
  const Eigen::Vector3d n(0, 0, -1), l(0, 0, -1),
      view = -Eigen::Vector3d((u - 319.5) / 600.0, (v - 239.5) / 600.0, 1).normalized();
  const double expected = 255 * 0.2 * 0.7 * n.dot((l + view).normalized());
  const double d = double(glossy.render(0, 0).at<std::uint8_t>(v, u)) -
                   double(clean.render(0, 0).at<std::uint8_t>(v, u));
  EXPECT_NEAR(d, expected, 1.0);
}

}  // namespace
}  // namespace netvmo::render
