// The sensor: mean radiance -> digital number, with Gaussian read noise and signal-dependent
// shot noise drawn per tile from a generator seeded by (seed, camera, frame, tile), so images do
// not depend on the number of threads or the order tiles are rendered in.
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

}  // namespace netvmo::render
