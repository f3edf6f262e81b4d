// The sensor: mean radiance -> digital number, with Gaussian read noise and signal-dependent
// shot noise drawn per tile from a generator seeded by (seed, camera, frame, tile), so images do
// not depend on the number of threads or the order tiles are rendered in.
#include <algorithm>
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

std::uint64_t splitmix64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Small deterministic Gaussian generator (Box-Muller on splitmix64), identical on every platform
// (std::normal_distribution is not specified bit-exactly).
class Gauss {
 public:
  explicit Gauss(std::uint64_t seed) : s_(seed) {}
  double operator()() {
    if (has_) {
      has_ = false;
      return spare_;
    }
    const double u1 = (double(splitmix64(s_) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    const double u2 = double(splitmix64(s_) >> 11) * (1.0 / 9007199254740992.0);
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2 * M_PI * u2);
    has_ = true;
    return r * std::cos(2 * M_PI * u2);
  }

 private:
  std::uint64_t s_;
  double spare_ = 0;
  bool has_ = false;
};

// std::clamp(std::lround(dn), 0, 255) (halves away from zero; NaN gives 0), without the libm
// call: within (0, 255) truncation is the floor and dn - floor(dn) is exact.
std::uint8_t to_dn(double dn) {
  if (!(dn > 0)) return 0;
  if (dn >= 255) return 255;
  const int r = int(dn);
  return std::uint8_t(dn - r >= 0.5 ? r + 1 : r);
}

}  // namespace

std::uint64_t tile_seed(std::uint64_t seed, int camera_id, int frame, int tile) {
  std::uint64_t s = seed;
  std::uint64_t h = splitmix64(s);
  s = h ^ (std::uint64_t(std::uint32_t(camera_id)) << 32 | std::uint32_t(frame));
  h = splitmix64(s);
  s = h ^ std::uint64_t(std::uint32_t(tile));
  return splitmix64(s);
}

void expose_tile(const Imaging& im, double scale, std::uint64_t seed, const std::vector<float>& acc,
                 int x0, int y0, int w, int h, cv::Mat& out) {
  Gauss gauss(seed);
  for (int y = 0; y < h; ++y) {
    auto* row = out.ptr<std::uint8_t>(y0 + y);
    for (int x = 0; x < w; ++x) {
      double dn = scale * acc[size_t(y * w + x)];
      if (im.noise) {
        const double var = im.read_noise * im.read_noise + im.shot_noise * std::max(dn, 0.0);
        dn += std::sqrt(var) * gauss();
      }
      row[x0 + x] = to_dn(dn);
    }
  }
}

namespace {

// Separable Gaussian of standard deviation sigma [px] over a w x h image, edges replicated.
void gaussian_blur(std::vector<double>& img, int w, int h, double sigma) {
  const int rad = int(std::ceil(3.5 * sigma));
  std::vector<double> k(size_t(2 * rad + 1));
  double sum = 0;
  for (int i = -rad; i <= rad; ++i)
    sum += k[size_t(i + rad)] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& x : k) x /= sum;
  std::vector<double> tmp(img.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double a = 0;
      for (int i = -rad; i <= rad; ++i)
        a += k[size_t(i + rad)] * img[size_t(y * w + std::clamp(x + i, 0, w - 1))];
      tmp[size_t(y * w + x)] = a;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double a = 0;
      for (int i = -rad; i <= rad; ++i)
        a += k[size_t(i + rad)] * tmp[size_t(std::clamp(y + i, 0, h - 1) * w + x)];
      img[size_t(y * w + x)] = a;
    }
}

// Saturation at the full well; a fraction `bloom` of each overflow goes to the 4 neighbours
// (spilling on while they overflow, at most 64 rounds), the rest is lost.
void full_well(std::vector<double>& img, int w, int h, double well, double bloom) {
  std::vector<double> spill(img.size());
  for (int round = 0; round < 64; ++round) {
    bool any = false;
    std::fill(spill.begin(), spill.end(), 0.0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double& s = img[size_t(y * w + x)];
        if (s <= well) continue;
        const double share = 0.25 * bloom * (s - well);
        s = well;
        if (share <= 1e-6) continue;
        any = true;
        if (x > 0) spill[size_t(y * w + x - 1)] += share;
        if (x + 1 < w) spill[size_t(y * w + x + 1)] += share;
        if (y > 0) spill[size_t((y - 1) * w + x)] += share;
        if (y + 1 < h) spill[size_t((y + 1) * w + x)] += share;
      }
    if (!any) return;
    for (size_t i = 0; i < img.size(); ++i) img[i] += spill[i];
  }
}

double tone_curve(const SensorModel& sm, double v) {
  v = std::clamp(v, 0.0, 1.0);
  switch (sm.tone) {
    case SensorModel::Tone::Linear:
      return v;
    case SensorModel::Tone::Srgb:  // IEC 61966-2-1 encoding
      return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    case SensorModel::Tone::Gamma:
      return std::pow(v, 1 / sm.gamma);
  }
  return v;
}

}  // namespace

void develop_image(const SensorModel& sm, const Imaging& im, const Intrinsics& K, double scale,
                   int camera_id, int frame, const std::vector<float>& acc, cv::Mat& out) {
  const int w = K.width, h = K.height;
  std::vector<double> S(acc.size());
  for (size_t i = 0; i < acc.size(); ++i) S[i] = scale * acc[i];
  if (sm.vignetting != SensorModel::Vignetting::None) {
    const double half_diag = 0.5 * std::hypot(double(w), double(h));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double V;
        if (sm.vignetting == SensorModel::Vignetting::Cos4) {
          const double xn = (x - K.cx) / K.fx, yn = (y - K.cy) / K.fy;
          const double q = 1 + xn * xn + yn * yn;
          V = 1 / (q * q);
        } else {
          const double r2 =
              (std::pow(x - K.cx, 2) + std::pow(y - K.cy, 2)) / (half_diag * half_diag);
          const auto& a = sm.vignetting_poly;
          V = 1 + r2 * (a[0] + r2 * (a[1] + r2 * a[2]));
        }
        S[size_t(y * w + x)] *= std::max(V, 0.0);
      }
  }
  if (sm.psf_sigma > 0) gaussian_blur(S, w, h, sm.psf_sigma);
  if (sm.full_well > 0) full_well(S, w, h, sm.full_well, sm.bloom);
  // With sharpening the encoded image is kept whole for the unsharp mask, else each pixel goes
  // straight to 8 bits.
  std::vector<double> E(sm.sharpen_amount > 0 ? S.size() : 0);
  const int tiles_x = (w + im.tile - 1) / im.tile, tiles_y = (h + im.tile - 1) / im.tile;
  for (int tile = 0; tile < tiles_x * tiles_y; ++tile) {
    Gauss gauss(tile_seed(im.seed, camera_id, frame, tile));
    const int x0 = (tile % tiles_x) * im.tile, y0 = (tile / tiles_x) * im.tile;
    for (int y = y0; y < std::min(h, y0 + im.tile); ++y) {
      auto* row = out.ptr<std::uint8_t>(y);
      for (int x = x0; x < std::min(w, x0 + im.tile); ++x) {
        double dn = S[size_t(y * w + x)];
        if (im.noise) {
          const double var = im.read_noise * im.read_noise + im.shot_noise * std::max(dn, 0.0);
          dn += std::sqrt(var) * gauss();
        }
        const double encoded = 255.0 * tone_curve(sm, sm.gain * dn / 255.0);
        if (E.empty())
          row[x] = to_dn(encoded);
        else
          E[size_t(y * w + x)] = encoded;
      }
    }
  }
  if (E.empty()) return;
  std::vector<double> G = E;
  gaussian_blur(G, w, h, sm.sharpen_sigma);
  const double a = sm.sharpen_amount;
  for (int y = 0; y < h; ++y) {
    auto* row = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y * w + x);
      row[x] = to_dn(E[i] + a * (E[i] - G[i]));
    }
  }
}

}  // namespace netvmo::render
