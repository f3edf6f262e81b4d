// netvmo run: a dataset (rendered or recorded) through the front end and the networked
// observer, with baselines, evaluation, overlays and plots.
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "run_options.hpp"
#include "run_plots.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

void add_run(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/run", bag;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "run", "Run the networked observer on a dataset's images",
      "Writes OUT/estimates.csv, OUT/energies.csv, OUT/errors.csv, OUT/summary.json,\n"
      "OUT/energies.png, OUT/errors.png and OUT/overlays/ (per-camera MP4s, mosaic.mp4,\n"
      "mosaic.png). delta_i(t) is the front end's detection success. Moving cameras\n"
      "(cameras.csv): each frame's believed poses g_wi(t_k) and body velocities\n"
      "V_wi = log(g_wi(t_k)^-1 g_wi(t_k+1)) / dt feed the observer's -hat(V_wi) g_bar term.\n"
      "OUT is built in the temporary sibling OUT.partial-<pid> and swapped into place at the end\n"
      "(a killed run leaves the previous OUT intact); OUT.lock keeps a second command from\n"
      "writing OUT at the same time. OUT must not be the dataset folder or lie inside it.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder (netvmo render output or recorded)")
      ->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  add_run_options(*cmd, o->run);
  cmd->add_option("--calibration", o->run.calibration,
                  "netvmo calibrate's calibration.json: summary.json's g_star_localisation says "
                  "what the cameras' localisation error alone contributes to the distance between "
                  "g* and the true target pose (first order), next to the measured distance");
  cmd->add_option(
      "--bag", o->bag,
      "Also write the run as a ROS 2 bag (rosbag2, sqlite3) into this folder: each "
      "camera's overlay, camera info, measurement with covariance and estimate, and "
      "/tf, /tf_static (docs/ros2.md); built aside and put in place at the end, as OUT");
  cmd->callback([o, &exit_code] {
    exit_code = guarded("run", [&] {
      to_image_run_options(o->run);  // option ranges first
      io::check_output_apart(o->out, o->dataset);
      std::optional<io::OutputDir> bag;
      if (!o->bag.empty()) {
        io::check_output_apart(o->bag, o->dataset);
        if (fs::weakly_canonical(o->bag) == fs::weakly_canonical(o->out))
          throw InputError("--bag " + o->bag + ": the same folder as --out");
      }
      io::OutputDir out(o->out, "run");
      if (!o->bag.empty()) bag.emplace(o->bag, "run --bag");
      auto source = sources::open_dataset_source(o->dataset, {}, o->run.keep_going);
      const auto summary =
          run_and_report(*source, o->run, out.path(), o->out, bag ? bag->path() : fs::path());
      out.commit();
      if (bag) bag->commit();
      print_run_summary(summary, o->out);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
