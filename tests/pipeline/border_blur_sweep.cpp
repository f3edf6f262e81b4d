// Test utility: how the border check's thickness test treats blurred tags, correct and wrong.
// Synthesizes camera pictures (testing::render_camera_picture: black ink at --black of the
// white 230, Gaussian blur sigma in linear light, encoding v^(1/gamma), noise sigma 2) of 20
// tags (4 random poses, seeded, at each of 2.5, 3, 4, 5 and 6 m: cells of 6 to 2.4 px) for each
// blur sigma, decodes each without the check (decimate 1), and runs check_border on the decoded
// (correct) quad and on wrong quads made from it by moving one side 1 or 1.5 px in or out,
// once with the fixed limit (border_blur_allowance 0) and once with the default allowance.
// Prints per sigma: correct quads decoded, their largest corner error, how many each setting
// rejects; wrong quads with a corner more than 1 px from the truth, how many each accepts.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <random>

#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "synth.hpp"

using namespace netvmo;
using namespace netvmo::frontend;

using testing::max_corner_error;

int main(int argc, char** argv) {
  CLI::App app{"Border check on blurred, gamma-encoded synthesized tags (test utility)"};
  double gamma = 2.2, black = 0.05;
  std::uint64_t seed = 7;
  app.add_option("--gamma", gamma, "Encoding v^(1/gamma) of the linear picture (1: linear)")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 4.0));
  app.add_option("--black", black, "Black ink reflectance, fraction of the white")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.5));
  app.add_option("--seed", seed, "Seed of the poses and the noise")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const auto calib = testing::test_calibration();
  DetectorSettings unchecked;
  unchecked.border_check = false;
  unchecked.quad_decimate = 1.0;
  TagDetector detector(unchecked);
  DetectorSettings fixed;
  fixed.border_blur_allowance = 0.0;
  const DetectorSettings dflt;
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<obs::SE3> poses;
  for (double z : {2.5, 3.0, 4.0, 5.0, 6.0})
    for (int p = 0; p < 4; ++p) {
      const double dx = 0.1 * u(rng) * z, dy = 0.07 * u(rng) * z;
      const obs::Vec3 tilt(0.4 * u(rng), 0.4 * u(rng), 3.0 * u(rng));
      poses.push_back(testing::facing_pose(z, dx, dy, tilt));
    }
  std::printf("gamma %.2f, black %.2f, %zu poses, noise sigma 2, seed %llu\n", gamma, black,
              poses.size(), static_cast<unsigned long long>(seed));
  std::printf("%-8s %8s %10s %14s %16s %12s %14s %16s\n", "sigma", "decoded", "max err",
              "rejected fixed", "rejected default", "wrong quads", "accepted fixed",
              "accepted default");
  for (double sigma : {0.0, 0.5, 0.8, 1.0, 1.2, 1.5, 2.0}) {
    int decoded = 0, rej_fixed = 0, rej_dflt = 0, wrong = 0, acc_fixed = 0, acc_dflt = 0;
    double worst = 0.0;
    for (size_t p = 0; p < poses.size(); ++p) {
      const auto truth = testing::project_corners(calib, poses[p], 0.2);
      testing::SynthSettings opt;
      opt.black = black * opt.white;
      opt.noise_sigma = 2.0;
      opt.seed = seed + 100 * p + static_cast<std::uint64_t>(10 * sigma);
      const cv::Mat img =
          testing::render_camera_picture(calib, {{0, 0.2, poses[p], {}}}, opt, sigma, gamma);
      const auto fd = detector.detect(img, &calib);
      if (!fd.target()) continue;
      ++decoded;
      const auto& c = fd.target()->corners;
      worst = std::max(worst, max_corner_error(c, truth));
      rej_fixed += !check_border(img, c, pattern, 8, fixed, &calib).ok;
      rej_dflt += !check_border(img, c, pattern, 8, dflt, &calib).ok;
      for (size_t k = 0; k < 4; ++k)
        for (double d : {-1.5, -1.0, 1.0, 1.5}) {
          const auto w = testing::move_side(c, k, d);
          if (max_corner_error(w, truth) <= 1.0) continue;
          ++wrong;
          acc_fixed += check_border(img, w, pattern, 8, fixed, &calib).ok;
          acc_dflt += check_border(img, w, pattern, 8, dflt, &calib).ok;
        }
    }
    std::printf("%-8.1f %8d %10.2f %14d %16d %12d %14d %16d\n", sigma, decoded, worst, rej_fixed,
                rej_dflt, wrong, acc_fixed, acc_dflt);
  }
  return 0;
}
