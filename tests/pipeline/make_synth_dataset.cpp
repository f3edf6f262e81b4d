// Test utility: writes a small synthesized dataset folder (network.yaml, calib/, cam_<id>/ or
// cam_<id>.avi, truth.csv, target.csv) for trying `netvmo detect` before the renderer exists.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "synth.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Write a synthesized tag dataset folder (test utility)"};
  std::string dir;
  int cameras = 3, frames = 10;
  bool video = false;
  double noise = 2.0;
  app.add_option("dir", dir, "Output dataset folder")->required();
  app.add_option("--cameras", cameras, "Number of cameras")->capture_default_str();
  app.add_option("--frames", frames, "Number of frames")->capture_default_str();
  app.add_option("--noise", noise, "Gaussian noise sigma (gray levels)")->capture_default_str();
  app.add_flag("--video", video, "Write cam_<id>.avi (MJPG) instead of image folders");
  CLI11_PARSE(app, argc, argv);
  auto spec = netvmo::testing::simple_dataset_spec(cameras, frames, video);
  spec.options.noise_sigma = noise;
  netvmo::testing::write_synth_dataset(dir, spec);
  std::printf("wrote %s: %d cameras, %d frames\n", dir.c_str(), cameras, frames);
  return 0;
}
