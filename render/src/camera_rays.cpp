// Camera rays: the sample pattern within a pixel, each camera's field-of-view bounds in
// undistorted normalized coordinates and, for a camera with distortion, the undistorted ray of
// every (pixel, sample), inverted once when the renderer is built.
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

double radical_inverse2(unsigned i) {
  double r = 0, f = 0.5;
  while (i) {
    if (i & 1) r += f;
    i >>= 1;
    f *= 0.5;
  }
  return r;
}

// Bounding box of the undistorted normalized coordinates of the image border.
void fov_bounds(const Intrinsics& Kc, CameraCache& cc) {
  cc.xmin = cc.ymin = std::numeric_limits<double>::infinity();
  cc.xmax = cc.ymax = -std::numeric_limits<double>::infinity();
  auto extend = [&](double u, double v) {
    const auto x = Kc.unproject(Vec2(u, v));
    if (!x) return;
    cc.xmin = std::min(cc.xmin, x->x());
    cc.xmax = std::max(cc.xmax, x->x());
    cc.ymin = std::min(cc.ymin, x->y());
    cc.ymax = std::max(cc.ymax, x->y());
  };
  const double W = Kc.width - 0.5, H = Kc.height - 0.5;
  for (int i = 0; i <= 64; ++i) {
    const double a = i / 64.0;
    extend(-0.5 + a * Kc.width, -0.5);
    extend(-0.5 + a * Kc.width, H);
    extend(-0.5, -0.5 + a * Kc.height);
    extend(W, -0.5 + a * Kc.height);
  }
}

// The pixel's own shift of the sample pattern, in [0, 1)^2, drawn from `key`
// (pixel_jitter_key(), non-zero).
Eigen::Vector2f pixel_shift(std::uint64_t key, int col, int row) {
  const std::uint64_t h =
      mix64(key ^ (std::uint64_t(std::uint32_t(row)) << 32 | std::uint32_t(col)));
  // Two 24-bit fractions of the pixel; float keeps 24 bits.
  return {float(h >> 40) * (1.0f / 16777216.0f),
          float((h >> 16) & 0xFFFFFF) * (1.0f / 16777216.0f)};
}

// Undistorted normalized coordinates of every (pixel, sample), the samples shifted per pixel for
// a non-zero `jitter_key`; NaN where the distortion model cannot be inverted.
std::vector<float> ray_table(const Intrinsics& Kc, const std::vector<Eigen::Vector2f>& offsets,
                             std::uint64_t jitter_key) {
  const int spp = int(offsets.size());
  std::vector<float> table(size_t(Kc.width) * size_t(Kc.height) * size_t(spp) * 2);
  for (int r = 0; r < Kc.height; ++r)
    for (int col = 0; col < Kc.width; ++col) {
      const Eigen::Vector2f shift =
          jitter_key ? pixel_shift(jitter_key, col, r) : Eigen::Vector2f::Zero();
      for (int s = 0; s < spp; ++s) {
        const Eigen::Vector2f o =
            jitter_key ? shifted_sample(offsets[size_t(s)], shift) : offsets[size_t(s)];
        const auto x = Kc.unproject(Vec2(col + o.x(), r + o.y()));
        const size_t i = ray_table_index(r, col, s, Kc.width, spp);
        table[i] = x ? float(x->x()) : std::numeric_limits<float>::quiet_NaN();
        table[i + 1] = x ? float(x->y()) : std::numeric_limits<float>::quiet_NaN();
      }
    }
  return table;
}

}  // namespace

std::vector<Eigen::Vector2f> sample_offsets(int spp) {
  std::vector<Eigen::Vector2f> out;
  const int n = int(std::lround(std::sqrt(double(spp))));
  if (n * n == spp) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        out.emplace_back(float((i + 0.5) / n - 0.5), float((j + 0.5) / n - 0.5));
  } else {
    for (int i = 0; i < spp; ++i)
      out.emplace_back(float((i + 0.5) / spp - 0.5),
                       float(radical_inverse2(unsigned(i)) + 0.5 / spp - 0.5));
  }
  return out;
}

std::uint64_t pixel_jitter_key(const Imaging& im, int camera_id) {
  if (im.sampling == Imaging::Sampling::Grid) return 0;
  const std::uint64_t k = mix64(mix64(im.seed ^ 0x6a09e667f3bcc909ULL) ^ std::uint32_t(camera_id));
  return k ? k : 1;
}

CameraCache make_camera_cache(const Intrinsics& Kc, const std::vector<Eigen::Vector2f>& offsets,
                              std::uint64_t jitter_key) {
  CameraCache cc;
  fov_bounds(Kc, cc);
  cc.width = Kc.width;
  cc.height = Kc.height;
  cc.spp = int(offsets.size());
  cc.fx = float(Kc.fx), cc.fy = float(Kc.fy), cc.cx = float(Kc.cx), cc.cy = float(Kc.cy);
  if (Kc.has_distortion()) {
    cc.table = ray_table(Kc, offsets, jitter_key);
  } else if (jitter_key) {
    cc.shift.reserve(size_t(Kc.width) * size_t(Kc.height));
    for (int r = 0; r < Kc.height; ++r)
      for (int col = 0; col < Kc.width; ++col) cc.shift.push_back(pixel_shift(jitter_key, col, r));
  }
  return cc;
}

}  // namespace netvmo::render
