// netvmo demo: the default scenario end to end: render -> detect -> networked observer ->
// results, overlays and plots.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"
#include "run_options.hpp"
#include "scenario_path.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

void add_demo(CLI::App& app, int& exit_code) {
  struct Options {
    std::string out = "results/demo";
    std::string scenario = "datasets/paper5_render.yaml";
    int frames = 0;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "demo",
      "Render the default scenario, run the networked observer on it, evaluate and plot",
      "Writes OUT/dataset/ (the rendered images, calibration, network.yaml and ground truth) and\n"
      "the results of `netvmo run` on it in OUT/ (estimates.csv, energies.csv, errors.csv,\n"
      "summary.json, energies.png, errors.png, overlays/).");
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--scenario", o->scenario, "Render scenario")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames to render (0 = the scenario's), at most 100000")
      ->capture_default_str()
      ->check(CLI::Range(0, io::kMaxDatasetFrames));
  add_run_options(*cmd, o->run);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("demo", [&] {
      to_image_run_options(o->run);  // option ranges first
      const fs::path scenario = find_scenario(o->scenario);
      io::OutputDir out_dir(o->out, "demo");
      // Everything is written into the temporary out_dir.path() and renamed to --out at the end:
      // what is printed (and summary.json's dataset) names the final paths.
      const fs::path out = out_dir.path(), dataset = out / "dataset";
      const fs::path shown = o->out, shown_dataset = shown / "dataset";
      std::printf("rendering %s into %s\n", scenario.string().c_str(),
                  shown_dataset.string().c_str());
      render::Renderer renderer(io::load_render_scenario(scenario));
      io::DatasetSettings dopt;
      dopt.frames = o->frames;
      io::write_dataset(renderer, dataset, dopt);
      std::printf("running the networked observer on %s\n", shown_dataset.string().c_str());
      auto source = sources::open_dataset_source(dataset, {}, o->run.keep_going, shown_dataset);
      const auto summary = run_and_report(*source, o->run, out, shown);
      out_dir.commit();
      print_run_summary(summary, shown);
      std::printf("open %s/overlays/mosaic.png, %s/energies.png and %s/errors.png\n",
                  shown.string().c_str(), shown.string().c_str(), shown.string().c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
