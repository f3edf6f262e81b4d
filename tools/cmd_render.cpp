// netvmo render SCENARIO --out DATASET [--frames N] [--spp S] [--seed K]
// Renders a scenario with the Embree renderer into a dataset folder (datasets/README.md).
#include <algorithm>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"

namespace netvmo::tools {

void add_render(CLI::App& app, int& exit_code) {
  struct Options {
    std::string scenario, out;
    int frames = 0;
    int spp = 0;
    long long seed = -1;
    std::string resolution;
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "render", "Render a scenario into a dataset folder (Embree)",
      "Writes DATASET/cam_<id>/<frame>.png, calib/cam_<id>.yaml, network.yaml, cameras.csv\n"
      "(believed camera poses per image), truth.csv, target.csv and truth_cameras.csv (true\n"
      "camera poses per image); layout: datasets/README.md. Cameras may move (`motion:`).\n"
      "DATASET is built in DATASET.partial-<pid> and swapped into place at the end (a killed\n"
      "render leaves the previous DATASET intact); DATASET.lock keeps a second command from\n"
      "writing it at the same time. An existing DATASET is replaced only if netvmo render wrote\n"
      "it (or it is empty).");
  cmd->add_option("SCENARIO", o->scenario, "render scenario YAML, e.g. datasets/paper5_render.yaml")
      ->required();
  cmd->add_option("--out", o->out, "dataset folder to write (created if needed)")->required();
  cmd->add_option("--frames", o->frames,
                  "number of frames (0 = the scenario's frames), at most 100000 (5 cameras of "
                  "640x480 PNGs take ~1 MB a frame)")
      ->capture_default_str()
      ->check(CLI::Range(0, io::kMaxDatasetFrames));
  cmd->add_option("--spp", o->spp, "samples per pixel (0 = the scenario's imaging.spp)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--seed", o->seed, "noise seed (-1 = the scenario's imaging.seed)")
      ->capture_default_str()
      ->check(CLI::Range(-1LL, 9000000000000000LL));
  cmd->add_option("--resolution", o->resolution,
                  "WxH: every camera at this resolution instead of its own, the same aspect ratio "
                  "(the same camera with a finer or coarser sensor; render::CameraSpec::"
                  "set_resolution)");
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  cmd->callback([o, &exit_code]() {
    exit_code = guarded("render", [&]() {
      render::SceneDescription scene = io::load_render_scenario(o->scenario);
      if (o->spp > 0) scene.imaging.spp = o->spp;
      if (o->seed >= 0) scene.imaging.seed = static_cast<std::uint64_t>(o->seed);
      if (o->frames > 0) scene.frames = o->frames;
      if (!o->resolution.empty()) {
        int w = 0, h = 0;
        char tail = 0;
        if (std::sscanf(o->resolution.c_str(), "%dx%d%c", &w, &h, &tail) != 2)
          throw InputError("--resolution " + o->resolution +
                           ": expected WIDTHxHEIGHT, e.g. 1280x720");
        for (auto& c : scene.cameras) try {
            c.set_resolution(w, h);
          } catch (const std::invalid_argument& e) {
            throw InputError("--resolution: " + std::string(e.what()));
          }
      }
      if (scene.frames > io::kMaxDatasetFrames)
        throw InputError(o->scenario + ": frames: " + std::to_string(scene.frames) +
                         " is more than " + std::to_string(io::kMaxDatasetFrames) +
                         " frames (~1 MB of PNGs per frame for 5 cameras)");
      std::unique_ptr<render::Renderer> renderer;
      try {
        renderer = std::make_unique<render::Renderer>(scene);
      } catch (const std::invalid_argument& e) {
        throw InputError(o->scenario + ": " + e.what());
      }
      io::check_output_apart(o->out, {});
      io::OutputDir out(o->out, "render");
      io::DatasetSettings opt;
      opt.progress = !o->quiet;
      const auto summary = io::write_dataset(*renderer, out.path(), opt);
      out.commit();

      std::printf("wrote %s: %d frames x %zu cameras at %.6g fps, %d spp, seed %llu\n",
                  o->out.c_str(), summary.frames, summary.cameras.size(), scene.fps,
                  scene.imaging.spp, static_cast<unsigned long long>(scene.imaging.seed));
      std::printf(
          "camera  tag in view  tag visible   fictitious target at frame 0 (believed g_wi * true "
          "g_io)\n");
      for (size_t i = 0; i < summary.cameras.size(); ++i) {
        const auto& c = summary.cameras[i];
        const auto t0 = renderer->truth(int(i), 0);
        const render::Pose g_fict = scene.cameras[i].g_wi_believed * t0.g_io;
        const render::Vec3 p = g_fict.translation(), r = obs::log_so3(g_fict.linear());
        std::printf("%6d  %10.1f%%  %10.1f%%   p [%.3f %.3f %.3f]  r [%.3f %.3f %.3f]\n", c.id,
                    100.0 * c.frames_in_fov / std::max(1, c.images),
                    100.0 * c.frames_visible / std::max(1, c.images), p.x(), p.y(), p.z(), r.x(),
                    r.y(), r.z());
      }
      return 0;
    });
  });
}

}  // namespace netvmo::tools
