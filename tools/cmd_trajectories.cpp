// netvmo trajectories RESULTS [--dataset DATASET] [--out DIR]
// A result folder's estimates.csv (and the dataset's ground truth) as TUM trajectory files.
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"

namespace netvmo::tools {

void add_trajectories(CLI::App& app, int& exit_code) {
  struct Options {
    std::string results, dataset, out;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "trajectories",
      "Write a result folder's estimates as TUM trajectory files (for evo and other trajectory "
      "tools)",
      "Reads RESULTS/estimates.csv (netvmo run, demo, launch, merge or simulate) and writes into\n"
      "OUT (default RESULTS/trajectories) one file per camera, cam_<id>.txt, its estimate of the\n"
      "target's pose in the world as TUM lines 'timestamp tx ty tz qx qy qz qw' (seconds, metres,\n"
      "unit quaternion, qw >= 0); with --dataset also truth.txt, the true target pose from its\n"
      "target.csv. With several targets: target_<tag>_cam_<id>.txt and target_<tag>_truth.txt.\n"
      "E.g. evo_ape tum OUT/truth.txt OUT/cam_1.txt (docs/images.md, \"Trajectory files\").\n"
      "Written in OUT.partial-<pid> and swapped into place.");
  cmd->add_option("RESULTS", o->results, "result folder holding estimates.csv")->required();
  cmd->add_option("--dataset", o->dataset,
                  "the dataset the results were run on: also write its true target pose");
  cmd->add_option("--out", o->out, "output folder (default RESULTS/trajectories)");
  cmd->callback([o, &exit_code]() {
    exit_code = guarded("trajectories", [&]() {
      const std::string out = o->out.empty() ? o->results + "/trajectories" : o->out;
      std::optional<std::filesystem::path> dataset;
      if (!o->dataset.empty()) {
        io::check_output_apart(out, o->dataset);
        dataset = o->dataset;
      }
      io::OutputDir dir(out, "trajectories");
      const auto files = run::write_trajectories(o->results, dataset, dir.path());
      dir.commit();
      std::printf("wrote %s:", out.c_str());
      for (const auto& f : files) std::printf(" %s (%zu poses)", f.name.c_str(), f.poses);
      std::printf("%s\n", files.empty() ? " nothing (no camera had an estimate)" : "");
      return 0;
    });
  });
}

}  // namespace netvmo::tools
