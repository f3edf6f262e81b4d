// The pose-flip counter of summary.json (flips.hpp) on synthetic sequences: a smooth rotation
// with noise, k jumps inserted, gaps.
#include <gtest/gtest.h>

#include <random>

#include "netvmo/pipeline/run/flips.hpp"

namespace netvmo {
namespace {
using run::count_flips;

constexpr double kDeg = M_PI / 180.0;

// A target rocking about x at `step_deg` per frame (a triangle wave of +-10 deg), with seeded
// noise of `noise_deg` (standard deviation per axis), and a permanent extra rotation of
// `jump_deg` about a tilted axis composed in at each frame of `jumps` (so each is one jump).
std::vector<std::optional<obs::SE3>> rocking(int frames, double step_deg, double noise_deg,
                                             const std::vector<int>& jumps, double jump_deg,
                                             unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_deg * kDeg);
  std::vector<std::optional<obs::SE3>> out;
  obs::Mat3 offset = obs::Mat3::Identity();
  double angle = -10.0, dir = 1.0;
  for (int k = 0; k < frames; ++k) {
    for (int j : jumps)
      if (j == k) offset = obs::exp_so3(jump_deg * kDeg * obs::Vec3(1, 1, 0).normalized()) * offset;
    obs::SE3 g = obs::SE3::Identity();
    g.linear() = offset * obs::exp_so3(obs::Vec3(angle * kDeg, 0, 0)) *
                 obs::exp_so3(obs::Vec3(noise(rng), noise(rng), noise(rng)));
    g.translation() = obs::Vec3(0.1, -0.2, 1.5);
    out.push_back(g);
    angle += dir * step_deg;
    if (std::abs(angle) >= 10.0) dir = -dir;
  }
  return out;
}

TEST(Flips, KJumpsInsertedGiveKFlips) {
  const int frames = 200;
  // No jump: the true motion (0.67 deg/frame) plus noise (0.3 deg per axis) stays below 5 deg.
  const auto smooth = rocking(frames, 0.67, 0.3, {}, 0.0, 1);
  const auto none = count_flips(smooth, 5.0);
  EXPECT_EQ(none.flips, 0);
  EXPECT_EQ(none.pairs, frames - 1);
  EXPECT_LT(run::max_step_deg(smooth), 5.0);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    // k jumps of 12 deg (an IPPE flip at ~6 deg off the normal) at seeded frames >= 2 apart.
    std::mt19937 rng(seed);
    std::vector<int> at;
    for (int f = 1; f < frames; f += 2 + static_cast<int>(rng() % 20)) at.push_back(f);
    const auto seq = rocking(frames, 0.67, 0.3, at, 12.0, seed);
    const auto c = count_flips(seq, 5.0);
    EXPECT_EQ(c.flips, static_cast<int>(at.size())) << "seed " << seed;
    EXPECT_EQ(c.pairs, frames - 1);
    EXPECT_DOUBLE_EQ(c.rate(), static_cast<double>(at.size()) / (frames - 1));
  }
}

TEST(Flips, GapsBreakPairsAndThresholdIsStrict) {
  auto seq = rocking(10, 1.0, 0.0, {3, 7}, 20.0, 1);
  EXPECT_EQ(count_flips(seq, 5.0).flips, 2);
  seq[7].reset();  // the jump into frame 7 is no longer a pair, nor 7 -> 8
  const auto c = count_flips(seq, 5.0);
  EXPECT_EQ(c.flips, 1);
  EXPECT_EQ(c.pairs, 9 - 2);
  // A threshold above every step counts none; below the smooth step (1 deg) counts every pair.
  EXPECT_EQ(count_flips(seq, 30.0).flips, 0);
  EXPECT_EQ(count_flips(seq, 0.5).flips, c.pairs);
  EXPECT_EQ(count_flips({}, 5.0).pairs, 0);
  EXPECT_EQ(count_flips({}, 5.0).rate(), 0.0);
}

}  // namespace
}  // namespace netvmo
