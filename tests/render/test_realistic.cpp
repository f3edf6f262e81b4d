// The realistic camera model (docs/realistic_camera.md), each effect against a closed form on a
// fronto-parallel tag: ink spread moves the imaged black/white edge by ink_spread * cell px, a
// border's width moves its inner edge, a glossy print adds its Blinn-Phong term, a bent card is
// imaged where its cylinder puts it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

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

// A sharp edge between two plateaus, from the profile p sampled at pixel centres x0, x0 + 1,
// ...: p's first value is one plateau's level, its last the other's, and each pixel between
// adds the fraction of the first plateau it shows. Exact for an edge sharper than the profile
// at any sub-pixel position; the half-way crossing of edge_position is not where the edge
// falls inside a pixel (up to 0.09 px off, on top of the samples' own 1/8 px).
double sharp_edge(const std::vector<double>& p, double x0) {
  const double first = p.front(), last = p.back();
  double x = x0 + 0.5;
  for (size_t i = 1; i + 1 < p.size(); ++i) x += (p[i] - last) / (first - last);
  return x;
}

// Profiles across a vertical edge (columns u0..u1 of the mean of rows [r0, r1)) and across a
// horizontal one (rows v0..v1 of the mean of columns [c0, c1)).
double vertical_sharp_edge(const cv::Mat& img, int u0, int u1, int r0, int r1) {
  std::vector<double> p;
  for (int u = u0; u <= u1; ++u) p.push_back(column_mean(img, u, r0, r1));
  return sharp_edge(p, u0);
}
double horizontal_sharp_edge(const cv::Mat& img, int v0, int v1, int c0, int c1) {
  std::vector<double> p;
  for (int v = v0; v <= v1; ++v) {
    double s = 0;
    for (int u = c0; u < c1; ++u) s += img.at<std::uint8_t>(v, u);
    p.push_back(s / (c1 - c0));
  }
  return sharp_edge(p, v0);
}

// A card of curvature k, its centre 1 m in front of the camera and facing it: the point at arc
// length a along the tag's x axis and at y lies sin(k a) / k to the side and (1 - cos(k a)) / k
// further away (PrintModel::bend), so it is imaged at 319.5 + 600 sin(k a) / k / Z,
// 239.5 - 600 y / Z (the tag's y axis points up the image), Z = 1 + (1 - cos(k a)) / k.
Vec2 bent_pixel(double k, double a, double y) {
  const double Z = 1 + (1 - std::cos(k * a)) / k;
  return {319.5 + 600 * std::sin(k * a) / k / Z, 239.5 - 600 * y / Z};
}

// A sensor integrates over its pixels; the renderer samples them. The tag's left edge, shifted by
// a known fraction of a pixel, located from the mean of rows 185-295 (the border's whole
// height) by sharp_edge(), at 2 x 2 samples per pixel: grid sampling counts each pixel's
// coverage in halves alike in every row, so the edge is found up to 1/4 px off (0.22 px at
// these shifts); jittered sampling shifts each pixel's 2 x 2 pattern by the pixel's own offset,
// and the mean over 110 rows is within 3 standard errors of the closed form (at most 0.25 px
// per row, so 0.024 px).
TEST(RealisticSampling, JitteredSamplesLocateAnEdgeAlongThePixelColumns) {
  double grid_worst = 0, jittered_worst = 0;
  for (int k = 0; k < 8; ++k) {
    const double shift = 0.03 + k / 8.0, edge = kLeftEdge + shift;  // [px]
    auto error = [&](Imaging::Sampling sampling) {
      SceneDescription s = testing::single_tag_scene(
          testing::facing_pose(Vec3(shift / 600.0, 0, 1), Vec3::Zero()), 4);
      s.imaging.sampling = sampling;
      const cv::Mat img = Renderer(s).render(0, 0);
      return std::abs(vertical_sharp_edge(img, int(edge) - 4, int(edge) + 4, 185, 295) - edge);
    };
    grid_worst = std::max(grid_worst, error(Imaging::Sampling::Grid));
    jittered_worst = std::max(jittered_worst, error(Imaging::Sampling::Jittered));
  }
  EXPECT_GT(grid_worst, 0.2);
  EXPECT_LT(jittered_worst, 0.075);
  std::printf("edge located within %.3f px (grid) and %.3f px (jittered) of the truth\n",
              grid_worst, jittered_worst);
}

TEST(RealisticPrint, BentCardIsImagedWhereTheCylinderPutsIt) {
  for (double k : {4.0, -4.0}) {
    SceneDescription s = fronto_scene();
    s.target().tag.print.bend = k;
    Renderer r(s);
    const cv::Mat img = r.render(0, 0);
    // The sides along y stay straight: the left one at arc length -0.1 (2.7 px inside the flat
    // card's edge for k = 4, 0.4 px for k = -4). 4 x 4 samples per pixel: an edge is located to
    // within 1/8 px.
    const double left = bent_pixel(k, -0.1, 0).x();
    EXPECT_NEAR(vertical_sharp_edge(img, int(left) - 4, int(left) + 4, 200, 280), left, 0.13)
        << "bend " << k;
    // The top side (y = 0.1) bows: 60 px above the centre in the middle, 59.25 px (k = 4) or
    // 60.77 px (k = -4) at arc length -0.08 near its end.
    EXPECT_NEAR(horizontal_sharp_edge(img, 175, 184, 318, 322), 179.5, 0.13) << "bend " << k;
    const Vec2 end = bent_pixel(k, -0.08, 0.1);
    const int u = int(std::lround(end.x())), v = int(end.y());
    EXPECT_NEAR(horizontal_sharp_edge(img, v - 4, v + 4, u - 2, u + 3), end.y(), 0.13)
        << "bend " << k;
    // The truth's corners are the bent card's.
    const FrameTruth t = r.truth(0, 0);
    const double h = 0.1;
    const Vec2 expected[4] = {bent_pixel(k, -h, -h), bent_pixel(k, h, -h), bent_pixel(k, h, h),
                              bent_pixel(k, -h, h)};
    for (int c = 0; c < 4; ++c) {
      ASSERT_TRUE(t.corners[size_t(c)].has_value());
      EXPECT_LT((*t.corners[size_t(c)] - expected[c]).norm(), 1e-6) << "corner " << c;
    }
    EXPECT_DOUBLE_EQ(t.visible_fraction, 1.0);
  }
}

// The fronto-parallel tag's bitmap cell (r, c) covers u in 244.5 + 15 [c, c + 1] and v in
// 164.5 + 15 [r, r + 1] (10 cells of 15 px, centred on the principal point).
double column_u(double fc) {
  return 244.5 + kCellPx * fc;
}
double row_v(double fr) {
  return 164.5 + kCellPx * fr;
}

// Where a side's border is `w` cells wide, the grid line along its inner edge (bitmap line 2 on
// the left and the top, 8 on the right) lies w cells from the outer edge (line 1, 9): measured
// across the border next to a white data cell, the black ends at 244.5 + 15 (1 + w). The outer
// edge, the truth's corners and the other sides do not move; ink spread acts on the moved grid.
TEST(RealisticPrint, BorderWidthMovesTheInnerEdgeOfItsSideOnly) {
  SceneDescription s = fronto_scene();
  s.target().tag.print.border_width = {1.3, 1.0, 1.0, 0.7};  // top, right, bottom, left
  const TagTexture tex(s.target().tag);
  int left_row = -1, right_row = -1, top_col = -1;  // a white data cell next to each border
  for (int k = 2; k < 8; ++k) {
    if (left_row < 0 && !tex.dark(k, 2)) left_row = k;
    if (right_row < 0 && !tex.dark(k, 7)) right_row = k;
    if (top_col < 0 && !tex.dark(2, k)) top_col = k;
  }
  ASSERT_GE(left_row, 0);
  ASSERT_GE(right_row, 0);
  ASSERT_GE(top_col, 0);
  auto rows = [](int r) { return std::pair{int(row_v(r)) + 4, int(row_v(r + 1)) - 3}; };
  Renderer r(s);
  const cv::Mat img = r.render(0, 0);
  const auto [l0, l1] = rows(left_row);
  const double left_inner = column_u(1 + 0.7);  // 270.0
  // 4 x 4 samples per pixel: an edge is located to within 1/8 px.
  EXPECT_NEAR(edge_position(img, int(left_inner) - 6, int(left_inner) + 6, l0, l1), left_inner,
              0.13);
  EXPECT_NEAR(left_edge(img), kLeftEdge, 0.05);  // the outer edge stays
  const auto [r0, r1] = rows(right_row);
  const double right_inner = column_u(8);  // 364.5, the right side is one cell wide
  EXPECT_NEAR(edge_position(img, int(right_inner) - 6, int(right_inner) + 6, r0, r1), right_inner,
              0.13);
  const double top_inner = row_v(1 + 1.3);  // 199.0
  const int c0 = int(column_u(top_col)) + 4, c1 = int(column_u(top_col + 1)) - 3;
  EXPECT_NEAR(horizontal_sharp_edge(img, int(top_inner) - 6, int(top_inner) + 6, c0, c1), top_inner,
              0.13);
  const FrameTruth t = r.truth(0, 0);
  ASSERT_TRUE(t.corners[0].has_value());
  EXPECT_LT((*t.corners[0] - Vec2(column_u(1), row_v(9))).norm(), 1e-6);  // bottom left

  // Ink spread of 0.2 cell on the moved grid: both edges of the left border move 3 px into the
  // white.
  s.target().tag.print.ink_spread = 0.2;
  const cv::Mat inked = Renderer(s).render(0, 0);
  EXPECT_NEAR(edge_position(inked, int(left_inner) - 6 + 3, int(left_inner) + 6 + 3, l0, l1),
              left_inner + 0.2 * kCellPx, 0.13);
  EXPECT_NEAR(left_edge(inked), kLeftEdge - 0.2 * kCellPx, 0.13);
}

TEST(RealisticPrint, BorderWidthOutOfRangeIsRefused) {
  SceneDescription s = fronto_scene();
  s.target().tag.print.border_width = {1.0, 1.0, 1.6, 1.0};
  EXPECT_THROW(Renderer r(s), std::invalid_argument);
  s.target().tag.print.border_width = {0.5, 1.5, 1.0, 1.0};
  EXPECT_NO_THROW(Renderer r(s));
}

TEST(RealisticPrint, BendBeyondAQuarterTurnIsRefused) {
  SceneDescription s = fronto_scene();
  s.target().tag.print.bend = 10.1;  // 1.515 rad over half the 0.3 m printed card
  EXPECT_THROW(Renderer r(s), std::invalid_argument);
  s.target().tag.print.bend = -9.9;
  EXPECT_NO_THROW(Renderer r(s));
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

// A quiet-zone pixel of the fronto-parallel tag: albedo 0.85 lit by ambient 0.3 plus the light
// 0.7 along the normal, S = 255 * 0.85 = 216.75 DN on the linear scale.
constexpr int kWhiteU = 252, kWhiteV = 239;
constexpr double kWhiteS = 216.75;

std::uint8_t white_dn(const SensorModel& sm) {
  SceneDescription s = fronto_scene(4);
  s.cameras[0].sensor = sm;
  Renderer r(s);
  return r.render(0, 0).at<std::uint8_t>(kWhiteV, kWhiteU);
}

TEST(RealisticSensor, ToneCurveMapsAKnownRadianceToItsDn) {
  SensorModel sm;
  EXPECT_EQ(white_dn(sm), 217);  // clean: round(216.75)
  sm.tone = SensorModel::Tone::Srgb;
  const double v = kWhiteS / 255;
  EXPECT_EQ(white_dn(sm), std::lround(255 * (1.055 * std::pow(v, 1 / 2.4) - 0.055)));
  sm.tone = SensorModel::Tone::Gamma;
  sm.gamma = 1.8;
  EXPECT_EQ(white_dn(sm), std::lround(255 * std::pow(v, 1 / 1.8)));
  sm.tone = SensorModel::Tone::Linear;
  sm.gain = 0.5;
  EXPECT_EQ(white_dn(sm), std::lround(0.5 * kWhiteS));
  sm.gain = 1;
  sm.full_well = 150;  // saturates at the full well
  EXPECT_EQ(white_dn(sm), 150);
}

// Only the background (radiance 0.5, S = 127.5 DN) in view: the tag is behind the camera.
cv::Mat background_image(const SensorModel& sm) {
  SceneDescription s = fronto_scene(1);
  s.target().motion = Trajectory::fixed(testing::facing_pose(Vec3(0, 0, -5), Vec3::Zero()));
  s.cameras[0].sensor = sm;
  Renderer r(s);
  return r.render(0, 0);
}

TEST(RealisticSensor, VignettingFallsAsSpecifiedAtTheCorner) {
  SensorModel sm;
  sm.vignetting = SensorModel::Vignetting::Cos4;
  cv::Mat img = background_image(sm);
  const double xn = -319.5 / 600, yn = -239.5 / 600, q = 1 + xn * xn + yn * yn;
  EXPECT_NEAR(img.at<std::uint8_t>(0, 0), 127.5 / (q * q), 0.51);
  EXPECT_NEAR(img.at<std::uint8_t>(240, 320), 127.5, 0.51);
  sm.vignetting = SensorModel::Vignetting::Poly;
  sm.vignetting_poly = {-0.3, 0.05, 0};
  img = background_image(sm);
  const double rho2 = (319.5 * 319.5 + 239.5 * 239.5) / (400.0 * 400.0);
  EXPECT_NEAR(img.at<std::uint8_t>(479, 639), 127.5 * (1 - 0.3 * rho2 + 0.05 * rho2 * rho2), 0.51);
}

// 10 % to 90 % rise [px] of the edge profile of the mean of rows [r0, r1) between columns u0, u1.
double rise_width(const cv::Mat& img, int u0, int u1, int r0, int r1) {
  const double a = column_mean(img, u0, r0, r1), b = column_mean(img, u1, r0, r1);
  auto crossing = [&](double level) {
    for (int u = u0; u < u1; ++u) {
      const double p = column_mean(img, u, r0, r1), q = column_mean(img, u + 1, r0, r1);
      if ((p - level) * (q - level) <= 0 && p != q) return u + (p - level) / (p - q);
    }
    return std::nan("");
  };
  return std::abs(crossing(a + 0.9 * (b - a)) - crossing(a + 0.1 * (b - a)));
}

TEST(RealisticSensor, PsfBlursAnEdgeByItsSigma) {
  SceneDescription s = fronto_scene();
  s.cameras[0].sensor.psf_sigma = 2.0;
  Renderer r(s);
  // A Gaussian of sigma 2 px convolved with the 1 px pixel box: sigma^2 + 1/12, and the 10-90 %
  // rise of a blurred step is 2 * 1.2816 sigma.
  const double expected = 2 * 1.2816 * std::sqrt(4.0 + 1.0 / 12);
  EXPECT_NEAR(rise_width(r.render(0, 0), int(kLeftEdge) - 8, int(kLeftEdge) + 8, 200, 280),
              expected, 0.15 * expected);
}

// An unsharp mask of amount k and sigma s_m on the encoded picture: (1) the sharpened picture is
// the plain one's unsharp mask, DN' = DN + k (DN - G * DN), to within the two pictures' rounding
// to 8 bits (1/2 DN each, through 1 + k and k: at most 1 + k DN); (2) on an edge blurred by the
// PSF, whose profile is about that of a Gaussian of s^2 = psf^2 + 1/12 (with the pixel's box),
// the mask's blur of it is one of S^2 = s^2 + s_m^2, and the sharpened profile is
//   E'(x) = E(x) + k (W - B) (Phi(x / S) - Phi(x / s)),  E(x) = B + (W - B) (1 - Phi(x / s)),
// x the distance past the edge into the black (W, B the white and black levels): it rises above
// the white before the edge and dips below the black after it, by the closed form's extremes.
// (Near the edge's middle the rendered profile is 1-2 DN off the Gaussian model, which the mask
// doubles; the extremes lie where it is within 0.4 DN.)
TEST(RealisticSensor, SharpeningIsTheUnsharpMaskOfTheBlurredEdge) {
  constexpr double k = 1.0, sm = 1.5, psf = 1.5;
  SceneDescription s = fronto_scene();
  s.cameras[0].sensor.psf_sigma = psf;
  Renderer plain(s);
  s.cameras[0].sensor.sharpen_amount = k;
  s.cameras[0].sensor.sharpen_sigma = sm;
  Renderer sharp(s);
  const cv::Mat a = plain.render(0, 0), b = sharp.render(0, 0);
  // (1)
  cv::Mat p, g;
  a.convertTo(p, CV_64F);
  const int rad = int(std::ceil(3.5 * sm));
  cv::GaussianBlur(p, g, cv::Size(2 * rad + 1, 2 * rad + 1), sm, sm, cv::BORDER_REPLICATE);
  double worst = 0.0;
  for (int v = 0; v < b.rows; ++v)
    for (int u = 0; u < b.cols; ++u) {
      const double e =
          std::clamp((1 + k) * p.at<double>(v, u) - k * g.at<double>(v, u), 0.0, 255.0);
      worst = std::max(worst, std::abs(b.at<std::uint8_t>(v, u) - e));
    }
  EXPECT_LE(worst, 1 + k);
  // (2)
  const double W = column_mean(a, int(kLeftEdge) - 7, 200, 280);
  const double B = column_mean(a, int(kLeftEdge) + 8, 200, 280);
  const double sd = std::sqrt(psf * psf + 1.0 / 12), SD = std::sqrt(sd * sd + sm * sm);
  const auto Phi = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  double peak = 0.0, dip = 255.0, model_peak = 0.0, model_dip = 255.0;
  for (int u = int(kLeftEdge) - 7; u <= int(kLeftEdge) + 8; ++u) {
    const double x = u - kLeftEdge;
    const double e = B + (W - B) * (1 - Phi(x / sd)) + k * (W - B) * (Phi(x / SD) - Phi(x / sd));
    model_peak = std::max(model_peak, e);
    model_dip = std::min(model_dip, e);
    peak = std::max(peak, column_mean(b, u, 200, 280));
    dip = std::min(dip, column_mean(b, u, 200, 280));
  }
  EXPECT_GT(model_peak, W + 5) << "the closed form shows no overshoot at these settings";
  EXPECT_NEAR(peak, model_peak, 1.0) << "white level " << W;
  EXPECT_NEAR(dip, std::max(model_dip, 0.0), 1.0) << "black level " << B;
}

TEST(RealisticSensor, BloomSpillsIntoTheNeighbours) {
  SceneDescription s = fronto_scene(4);
  s.cameras[0].sensor.full_well = 150;
  Renderer none(s);
  s.cameras[0].sensor.bloom = 0.8;
  Renderer bloom(s);
  const cv::Mat a = none.render(0, 0), b = bloom.render(0, 0);
  // The first black column inside the tag's left edge gets charge from the white quiet zone;
  // a black pixel in the middle of the border cell, 7 px from any white, much less.
  const int near_u = int(kLeftEdge) + 1, far_u = int(kLeftEdge) + 8;
  EXPECT_GT(column_mean(b, near_u, 200, 280), column_mean(a, near_u, 200, 280) + 5);
  EXPECT_LT(column_mean(b, far_u, 200, 280) - column_mean(a, far_u, 200, 280),
            0.5 * (column_mean(b, near_u, 200, 280) - column_mean(a, near_u, 200, 280)));
  EXPECT_EQ(b.at<std::uint8_t>(kWhiteV, kWhiteU - 5), 150);  // saturated white stays at the well
}

TEST(RealisticSensor, SameSeedSameBytesOtherSeedOtherBytes) {
  auto image = [](std::uint64_t seed, int threads) {
    SceneDescription s = fronto_scene(4);
    s.cameras[0].sensor = SensorModel::realistic();
    s.target().tag.print = PrintModel::realistic();
    s.imaging.noise = true;
    s.imaging.seed = seed;
    s.imaging.threads = threads;
    Renderer r(s);
    return r.render(0, 0);
  };
  const cv::Mat a = image(3, 2), b = image(3, 1), c = image(4, 2);
  EXPECT_EQ(cv::countNonZero(a != b), 0);
  EXPECT_GT(cv::countNonZero(a != c), 1000);
}

// The fronto-parallel tag moving at v [m/s] along the image's x axis (1 m away: 600 v px/s).
SceneDescription moving_scene(double v, int spp) {
  SceneDescription s = fronto_scene(spp);
  s.target().motion.kind = Trajectory::Kind::Twist;
  // The flip about x (facing_pose) keeps the object's x axis along the camera's x.
  s.target().motion.twist << v, 0, 0, 0, 0, 0;
  return s;
}

TEST(RealisticTime, MotionBlurWidthIsVelocityTimesExposure) {
  SceneDescription s = moving_scene(1.0, 16);
  s.cameras[0].sensor.exposure_time = 1.0 / 60;  // 600 px/s * 1/60 s = 10 px
  Renderer r(s);
  const cv::Mat img = r.render(0, 0);
  // A step blurred by a box of width w has a linear ramp: its 10-90 % rise is 0.8 w (the pixel's
  // own 1 px box adds a little at the ends of the ramp only).
  EXPECT_NEAR(rise_width(img, int(kLeftEdge) - 12, int(kLeftEdge) + 12, 200, 280), 8.0, 0.4);
  // The exposure is centred on the frame's time: the half-way point stays at the true edge.
  EXPECT_NEAR(edge_position(img, int(kLeftEdge) - 12, int(kLeftEdge) + 12, 200, 280), kLeftEdge,
              0.25);
  EXPECT_NEAR(r.truth(0, 0).corners[0]->x(), kLeftEdge, 1e-6);  // truth at the frame's time
}

TEST(RealisticTime, MovingCameraBlursTheSameWay) {
  // The camera moving at -1 m/s along its x sees the static tag move at +600 px/s.
  SceneDescription s = fronto_scene(16);
  s.cameras[0].motion = Trajectory();
  s.cameras[0].motion->kind = Trajectory::Kind::Twist;
  s.cameras[0].motion->twist << -1.0, 0, 0, 0, 0, 0;
  s.cameras[0].sensor.exposure_time = 1.0 / 60;
  Renderer r(s);
  EXPECT_NEAR(rise_width(r.render(0, 0), int(kLeftEdge) - 12, int(kLeftEdge) + 12, 200, 280), 8.0,
              0.4);
}

TEST(RealisticTime, RollingShutterShearsAVerticalEdge) {
  SceneDescription s = moving_scene(1.0, 4);
  s.cameras[0].sensor.line_delay = 1e-4;  // row r at (r - 239.5) * 1e-4 s: 0.06 px per row
  Renderer r(s);
  const cv::Mat img = r.render(0, 0);
  const double top = edge_position(img, int(kLeftEdge) - 12, int(kLeftEdge) + 12, 200, 210);
  const double mid = edge_position(img, int(kLeftEdge) - 12, int(kLeftEdge) + 12, 235, 245);
  const double bottom = edge_position(img, int(kLeftEdge) - 12, int(kLeftEdge) + 12, 270, 280);
  EXPECT_NEAR(bottom - top, 600 * 1e-4 * 70, 0.2);
  EXPECT_NEAR(mid, kLeftEdge, 0.15);  // the middle row is exposed at the frame's time
}

// The tag of fronto_scene, its distance z and a thin lens of focal length 25 mm at f/1 (A =
// 25 mm) focused at d: the circle of confusion is fx A |1/z - 1/d| px across.
TEST(RealisticLens, DefocusBlurCircleFollowsTheThinLens) {
  const double A = 0.025, d = 2.0;
  SceneDescription s = fronto_scene(36);
  s.cameras[0].sensor.f_number = 1.0;
  s.cameras[0].sensor.focal_length_mm = 25;
  s.cameras[0].sensor.focus_distance = d;
  Renderer r(s);
  const double c = 600 * A * std::abs(1 / 1.0 - 1 / d);  // 7.5 px
  // A step blurred by a uniform disc of radius R: the fraction of the disc past x is
  // (acos(x / R) - (x / R) sqrt(1 - (x / R)^2)) / pi; its 10-90 % rise is 2 x90 with
  // (acos(u) - u sqrt(1 - u^2)) / pi = 0.1 at u = x90 / R.
  double lo = 0, hi = 1;
  for (int i = 0; i < 60; ++i) {
    const double u = 0.5 * (lo + hi);
    ((std::acos(u) - u * std::sqrt(1 - u * u)) / M_PI > 0.1 ? lo : hi) = u;
  }
  const double expected = 2 * lo * 0.5 * c;
  EXPECT_NEAR(rise_width(r.render(0, 0), int(kLeftEdge) - 10, int(kLeftEdge) + 10, 200, 280),
              expected, 0.1 * expected + 0.3);
  // In focus (d = 1 m, the tag's distance) the edge is as sharp as the pinhole's.
  s.cameras[0].sensor.focus_distance = 1.0;
  Renderer sharp(s), pinhole(fronto_scene(36));
  EXPECT_NEAR(rise_width(sharp.render(0, 0), int(kLeftEdge) - 10, int(kLeftEdge) + 10, 200, 280),
              rise_width(pinhole.render(0, 0), int(kLeftEdge) - 10, int(kLeftEdge) + 10, 200, 280),
              0.1);
}

}  // namespace
}  // namespace netvmo::render
