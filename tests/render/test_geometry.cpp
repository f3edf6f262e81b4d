// Geometry: the rendered tag's black border, located purely from the image (sub-pixel edge
// crossings fitted with straight lines, lines intersected), agrees with the analytic projection of
// the corners to better than 0.1 px at 640x480 with 4x4 supersampling.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

struct Line {
  Vec2 point, dir;
};

// Total least squares line through points.
Line fit_line(const std::vector<Vec2>& pts) {
  Vec2 mean = Vec2::Zero();
  for (const auto& p : pts) mean += p;
  mean /= double(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  return {mean, es.eigenvectors().col(1)};
}

Vec2 intersect(const Line& a, const Line& b) {
  Eigen::Matrix2d A;
  A.col(0) = a.dir;
  A.col(1) = -b.dir;
  const Vec2 st = A.colPivHouseholderQr().solve(b.point - a.point);
  return a.point + st.x() * a.dir;
}

// Sub-pixel crossings of the mid grey level along image columns (near-horizontal edge) or rows
// (near-vertical edge) for the central 70% of the segment a-b. `a`, `b` only position the search
// window (+-4 px); the crossing itself is measured in the image.
std::vector<Vec2> edge_points(const cv::Mat& img, const Vec2& a, const Vec2& b) {
  std::vector<Vec2> pts;
  const Vec2 d = b - a;
  const bool horizontal = std::abs(d.x()) > std::abs(d.y());
  auto px = [&](int r, int c) { return double(img.at<uint8_t>(r, c)); };
  const double lo = horizontal ? std::min(a.x(), b.x()) : std::min(a.y(), b.y());
  const double hi = horizontal ? std::max(a.x(), b.x()) : std::max(a.y(), b.y());
  const double len = hi - lo;
  for (int s = int(std::ceil(lo + 0.15 * len)); s <= int(std::floor(hi - 0.15 * len)); ++s) {
    // Predicted crossing coordinate along the scan line.
    const double f = horizontal ? (s - a.x()) / d.x() : (s - a.y()) / d.y();
    const double pred = horizontal ? a.y() + f * d.y() : a.x() + f * d.x();
    const int c0 = int(std::floor(pred));
    auto val = [&](int k) { return horizontal ? px(k, s) : px(s, k); };
    const double v1 = val(c0 - 4), v2 = val(c0 + 5);
    const double mid = 0.5 * (v1 + v2);
    double best = 1e9, pos = 0;
    for (int k = c0 - 4; k < c0 + 5; ++k) {
      const double p = val(k), q = val(k + 1);
      if ((p - mid) * (q - mid) <= 0 && p != q) {
        const double x = k + (mid - p) / (q - p);
        if (std::abs(x - pred) < best) {
          best = std::abs(x - pred);
          pos = x;
        }
      }
    }
    if (best > 3) continue;
    pts.push_back(horizontal ? Vec2(s, pos) : Vec2(pos, s));
  }
  return pts;
}

void check_pose(const Pose& g_wo) {
  Renderer r(testing::single_tag_scene(g_wo, /*spp=*/16));
  const cv::Mat img = r.render(0, 0);
  const FrameTruth gt = r.truth(0, 0);
  ASSERT_TRUE(gt.in_fov);
  std::array<Vec2, 4> c;
  for (int k = 0; k < 4; ++k) c[size_t(k)] = *gt.corners[size_t(k)];
  std::array<Line, 4> lines;  // edge k joins corner k and k+1
  for (int k = 0; k < 4; ++k) {
    const auto pts = edge_points(img, c[size_t(k)], c[size_t((k + 1) % 4)]);
    ASSERT_GT(pts.size(), 30u) << "edge " << k;
    lines[size_t(k)] = fit_line(pts);
  }
  for (int k = 0; k < 4; ++k) {
    const Vec2 measured = intersect(lines[size_t((k + 3) % 4)], lines[size_t(k)]);
    const double err = (measured - c[size_t(k)]).norm();
    std::printf("corner %d: analytic (%.3f, %.3f) rendered (%.3f, %.3f) error %.4f px\n", k,
                c[size_t(k)].x(), c[size_t(k)].y(), measured.x(), measured.y(), err);
    EXPECT_LT(err, 0.1) << "corner " << k;
  }
}

TEST(Geometry, RenderedBorderCornersMatchProjection) {
  check_pose(testing::facing_pose(Vec3(0.07, -0.05, 1.0), Vec3(0.35, -0.3, 0.4)));
}

TEST(Geometry, RenderedBorderCornersMatchProjectionSecondPose) {
  check_pose(testing::facing_pose(Vec3(-0.12, 0.08, 0.8), Vec3(-0.2, 0.45, -1.1)));
}

// The same camera at twice and at three quarters of its resolution (CameraSpec::set_resolution):
// every projected point moves to (u + 1/2) s - 1/2, distortion included, and the image keeps its
// aspect.
TEST(Geometry, AnotherResolutionIsTheSameCameraScaled) {
  SceneDescription scene = testing::single_tag_scene(
      testing::facing_pose(Vec3(0.07, -0.05, 1.0), Vec3(0.35, -0.3, 0.4)));
  scene.cameras[0].intrinsics.dist = {-0.08, 0.02, 0.001, -0.001, 0.0, 0.0, 0.0, 0.0};
  scene.cameras[0].sensor.line_delay = 2e-5;
  const Intrinsics k = scene.cameras[0].intrinsics;
  for (const auto& [w, h] : {std::pair{1280, 960}, std::pair{k.width * 3 / 4, k.height * 3 / 4}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    CameraSpec c = scene.cameras[0];
    c.set_resolution(w, h);
    const double s = static_cast<double>(w) / k.width;
    EXPECT_EQ(c.intrinsics.height, h);
    EXPECT_DOUBLE_EQ(c.sensor.line_delay * h, 2e-5 * k.height);  // the same readout time
    for (const Vec3& p : {Vec3(0.1, -0.05, 1.0), Vec3(-0.3, 0.2, 0.9), Vec3(0.2, 0.25, 1.4)}) {
      const auto a = k.project(p), b = c.intrinsics.project(p);
      ASSERT_TRUE(a && b);
      EXPECT_NEAR(b->x(), (a->x() + 0.5) * s - 0.5, 1e-9);
      EXPECT_NEAR(b->y(), (a->y() + 0.5) * s - 0.5, 1e-9);
    }
  }
  CameraSpec c = scene.cameras[0];
  EXPECT_THROW(c.set_resolution(1280, 720), std::invalid_argument);  // 4:3 -> 16:9
}

}  // namespace
}  // namespace netvmo::render
