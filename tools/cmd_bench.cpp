// netvmo bench: network frames per second of the whole pipeline, on recorded data (decode +
// detection + observer) and on live rendering (render + detection + observer).
#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"
#include "netvmo/render/renderer.hpp"
#include "scenario_path.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {
void report(const char* what, const run::ImageRunResult& r, size_t cameras) {
  const double frames = static_cast<double>(r.history.size());
  std::printf(
      "%-36s %6.1f network frames/s  (%zu cameras; per network frame: %.1f ms front end%s, %.2f ms "
      "observer)\n",
      what, frames / r.seconds, cameras, 1000.0 * r.seconds_front_end / frames,
      std::string(what).find("live") != std::string::npos ? " incl. rendering" : " incl. decoding",
      1000.0 * r.seconds_observer / frames);
}
}  // namespace

void add_bench(CLI::App& app, int& exit_code) {
  struct Options {
    std::string scenario = "datasets/paper5_render.yaml";
    std::string moving = "datasets/moving_target.yaml";
    int frames = 60;
    int live_spp = 1;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "bench", "Network frames per second of the whole pipeline, recorded and live");
  cmd->add_option("--scenario", o->scenario,
                  "Render scenario (static: live frames reuse the radiance)")
      ->capture_default_str();
  cmd->add_option("--moving-scenario", o->moving,
                  "Scenario with moving bodies, rendered live (re-tracing where bodies moved, and "
                  "again traced in full every frame)")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames per measurement")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--live-spp", o->live_spp, "Samples per pixel for live rendering")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("bench", [&] {
      const fs::path scenario = find_scenario(o->scenario);
      const auto scene = io::load_render_scenario(scenario);
      run::ImageRunOptions run;
      run.progress = false;
      run.max_frames = o->frames;
      // Recorded: render a dataset first (not timed), then decode + detect + observe.
      const fs::path tmp =
          fs::temp_directory_path() / ("netvmo_bench_" + std::to_string(::getpid()));
      {
        render::Renderer renderer(scene);
        io::DatasetOptions d;
        d.frames = o->frames;
        d.progress = false;
        std::printf("rendering %d frames of %s for the recorded measurement...\n", o->frames,
                    scenario.string().c_str());
        io::write_dataset(renderer, tmp, d);
      }
      auto recorded = sources::open_dataset_source(tmp);
      const auto r1 = run::run_images(*recorded, run);
      report("recorded (PNG decode+detect+observe)", r1, scene.cameras.size());
      fs::remove_all(tmp);
      auto live_scene = scene;
      live_scene.imaging.spp = o->live_spp;
      auto live = sources::make_render_source(live_scene, o->frames);
      const auto r2 = run::run_images(*live, run);
      char label[96];
      std::snprintf(label, sizeof label, "live, static scene (%d spp)", o->live_spp);
      report(label, r2, scene.cameras.size());
      auto moving_scene = io::load_render_scenario(find_scenario(o->moving));
      moving_scene.imaging.spp = o->live_spp;
      auto live_moving =
          sources::make_render_source(moving_scene, std::min(o->frames, moving_scene.frames));
      const auto r3 = run::run_images(*live_moving, run);
      std::snprintf(label, sizeof label, "live, moving scene (%d spp)", o->live_spp);
      report(label, r3, moving_scene.cameras.size());
      moving_scene.imaging.reuse_radiance = false;
      auto live_full =
          sources::make_render_source(moving_scene, std::min(o->frames, moving_scene.frames));
      const auto r4 = run::run_images(*live_full, run);
      std::snprintf(label, sizeof label, "live, moving, no reuse (%d spp)", o->live_spp);
      report(label, r4, moving_scene.cameras.size());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
