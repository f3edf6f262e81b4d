#include "netvmo/render/texture.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "netvmo/render/tag_family.hpp"

namespace netvmo::render {
namespace {

// Lattice value in [-1, 1): a short integer hash of the cell and the seed.
inline float lattice(std::int32_t i, std::int32_t j, std::int32_t k, std::uint32_t seed) {
  std::uint32_t h = std::uint32_t(i) * 0x8da6b343U ^ std::uint32_t(j) * 0xd8163841U ^
                    std::uint32_t(k) * 0xcb1ab31fU ^ seed;
  h ^= h >> 15;
  h *= 0x2c1b3c6dU;
  h ^= h >> 12;
  h *= 0x297a2d39U;
  h ^= h >> 15;
  return float(h >> 8) * (2.0f / 16777216.0f) - 1.0f;
}

inline float smooth(float t) {
  return t * t * (3 - 2 * t);
}

// Trilinear value noise in [-1, 1] (single precision: this is the renderer's hot texture path).
float value_noise(float x, float y, float z, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const auto i = std::int32_t(fx), j = std::int32_t(fy), k = std::int32_t(fz);
  const float tx = smooth(x - fx), ty = smooth(y - fy), tz = smooth(z - fz);
  auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
  const float x00 = lerp(lattice(i, j, k, seed), lattice(i + 1, j, k, seed), tx);
  const float x10 = lerp(lattice(i, j + 1, k, seed), lattice(i + 1, j + 1, k, seed), tx);
  const float x01 = lerp(lattice(i, j, k + 1, seed), lattice(i + 1, j, k + 1, seed), tx);
  const float x11 = lerp(lattice(i, j + 1, k + 1, seed), lattice(i + 1, j + 1, k + 1, seed), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

}  // namespace

TagTexture::TagTexture(const TagSpec& spec) : spec_(spec) {
  if (!(spec.size > 0)) throw std::invalid_argument("tag size must be positive");
  if (spec.quiet_cells < 0) throw std::invalid_argument("tag quiet_cells must be >= 0");
  if (!(std::abs(spec.print.ink_spread) <= 0.5))
    throw std::invalid_argument("tag print.ink_spread must be between -0.5 and 0.5 cells");
  if (!(spec.print.gloss >= 0 && spec.print.gloss <= 1))
    throw std::invalid_argument("tag print.gloss must be between 0 and 1");
  if (!(spec.print.shininess >= 1 && spec.print.shininess <= 10000))
    throw std::invalid_argument("tag print.shininess must be between 1 and 10000");
  for (const double w : spec.print.border_width)
    if (!(w >= 0.5 && w <= 1.5))
      throw std::invalid_argument("tag print.border_width must be between 0.5 and 1.5 cells");
  even_border_ = spec.print.even_border();
  const TagFamilyPtr f = create_tag_family(spec.family);
  if (spec.id < 0 || static_cast<std::uint32_t>(spec.id) >= f->ncodes)
    throw std::invalid_argument("tag id " + std::to_string(spec.id) + " out of range for " +
                                spec.family + " (0.." + std::to_string(f->ncodes - 1) + ")");
  total_width_ = f->total_width;
  width_at_border_ = f->width_at_border;
  cell_ = spec.size / width_at_border_;
  if (!(std::abs(spec.print.bend) <= max_bend()))
    throw std::invalid_argument("tag print.bend must be " + bend_range());
  // image_u8_destroy is not exported by Debian's libapriltag 3.3; it frees the pixel buffer and
  // the struct, both allocated with calloc by image_u8_create_stride, so do the same here.
  auto free_image = [](image_u8_t* p) {
    if (p) std::free(p->buf);
    std::free(p);
  };
  std::unique_ptr<image_u8_t, decltype(free_image)> im(apriltag_to_image(f.get(), spec.id),
                                                       free_image);
  if (!im) throw std::runtime_error("apriltag_to_image failed");
  if (im->width != total_width_ || im->height != total_width_)
    throw std::runtime_error("apriltag_to_image returned an unexpected bitmap size");
  dark_.resize(static_cast<size_t>(total_width_ * total_width_));
  for (int r = 0; r < total_width_; ++r)
    for (int c = 0; c < total_width_; ++c)
      dark_[static_cast<size_t>(r * total_width_ + c)] = im->buf[r * im->stride + c] < 128 ? 1 : 0;
}

std::string TagTexture::bend_range() const {
  std::ostringstream msg;
  msg.precision(3);
  msg << "within +-" << max_bend() << " 1/m for this tag (" << kMaxBendAngle
      << " rad over half its printed side)";
  return msg.str();
}

Vec3 TagTexture::card_point(double u, double y) const {
  const double k = spec_.print.bend;
  if (k == 0) return Vec3(u, y, 0);
  return Vec3(std::sin(k * u) / k, y, -(1 - std::cos(k * u)) / k);
}

Vec3 TagTexture::card_normal(double u) const {
  const double k = spec_.print.bend;
  return Vec3(std::sin(k * u), 0, std::cos(k * u));
}

Mesh TagTexture::card_mesh() const {
  const double side = printed_side(), k = std::abs(spec_.print.bend);
  if (k == 0) return make_plane(side, side);
  // A strip of width w leaves the cylinder by its sagitta k w^2 / 8.
  constexpr double kSagitta = 2e-6;  // [m]
  const int strips = std::clamp(int(std::ceil(side * std::sqrt(k / (8 * kSagitta)))), 1, 4096);
  Mesh m;
  const double h = side / 2;
  for (int i = 0; i <= strips; ++i) {
    const double u = -h + side * i / strips;
    m.vertices.push_back(card_point(u, -h).cast<float>());
    m.vertices.push_back(card_point(u, h).cast<float>());
  }
  for (int i = 0; i < strips; ++i) {
    const auto a = std::uint32_t(2 * i), b = a + 2;  // a, b at y = -h; a + 1, b + 1 at y = h
    m.triangles.push_back({a, b, b + 1});
    m.triangles.push_back({a, b + 1, a + 1});
  }
  return m;
}

int TagTexture::grid_cell(double f, size_t a, size_t b, double& lo, double& hi) const {
  // The border's outer edges lie on grid lines o and total - o; its inner edges, one cell in,
  // move to o + width (side a) and total - o - width (side b).
  const int o = (total_width_ - width_at_border_) / 2;
  const auto& w = spec_.print.border_width;
  auto line = [&](int k) {
    if (k == o + 1) return o + w[a];
    if (k == total_width_ - o - 1) return total_width_ - o - w[b];
    return double(k);
  };
  int i = static_cast<int>(std::floor(f));
  // A moved line is at most half a cell from its place, so the cell is at most one off.
  if (f < line(i)) --i;
  if (f >= line(i + 1)) ++i;
  lo = line(i);
  hi = line(i + 1);
  return i;
}

double TagTexture::spread_albedo(double x, double y) const {
  const double f = spec_.print.ink_spread, d = std::abs(f);
  const double half = 0.5 * total_width_;
  const double fc = x / cell_ + half, fr = half - y / cell_;
  double c0, c1, r0, r1;  // the cell's grid lines [cells of the bitmap]
  const int c = grid_cell(fc, 3, 1, c0, c1), r = grid_cell(fr, 0, 2, r0, r1);
  const double u = fc - c0, v = fr - r0;  // position inside the cell [cells]
  const bool me = dark_or_white(r, c);
  // A point takes the other colour when a cell of the spreading colour (black for f > 0, white
  // for f < 0) lies within d cells of it; |f| <= 0.5 and cells at least 0.5 wide (border_width)
  // keep that to the 8 neighbours.
  const bool spreading_dark = f > 0;
  if (me == spreading_dark) return me ? spec_.black_albedo : spec_.white_albedo;
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      if ((dr == 0 && dc == 0) || dark_or_white(r + dr, c + dc) != spreading_dark) continue;
      const double ex = dc < 0 ? u : (dc > 0 ? (c1 - c0) - u : 0);
      const double ey = dr < 0 ? v : (dr > 0 ? (r1 - r0) - v : 0);
      if (ex * ex + ey * ey < d * d)
        return spreading_dark ? spec_.black_albedo : spec_.white_albedo;
    }
  return me ? spec_.black_albedo : spec_.white_albedo;
}

double Material::eval(const Vec3& p, const Vec3& n) const {
  switch (pattern) {
    case Pattern::Solid:
      return albedo;
    case Pattern::Checker: {
      int skip = 0;
      n.cwiseAbs().maxCoeff(&skip);
      long s = 0;
      for (int a = 0; a < 3; ++a)
        if (a != skip) s += long(std::floor(p[a] / scale));
      return (s & 1) ? albedo2 : albedo;
    }
    case Pattern::Noise: {
      // Two octaves of value noise, feature size `scale` and about scale / 2.
      const float q = float(1.0 / scale);
      const float x = float(p.x()) * q, y = float(p.y()) * q, z = float(p.z()) * q;
      const double n =
          0.7f * value_noise(x, y, z, seed * 0x9e3779b9U) +
          0.3f * value_noise(2.03f * x + 17.1f, 2.03f * y, 2.03f * z, seed * 0x9e3779b9U + 1);
      return std::clamp(albedo + albedo2 * n, 0.0, 1.0);
    }
  }
  return albedo;
}

Material::Pattern parse_pattern(const std::string& name) {
  if (name == "solid") return Material::Pattern::Solid;
  if (name == "checker") return Material::Pattern::Checker;
  if (name == "noise") return Material::Pattern::Noise;
  throw std::invalid_argument("unknown pattern '" + name + "' (use solid, checker or noise)");
}

}  // namespace netvmo::render
