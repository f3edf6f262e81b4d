// netvmo trajectories RESULTS [--dataset DATASET] [--out DIR] [--reference REF] [--align]
// [--max-dt S] [--reference-time-offset S] [--estimate-time-offset] [--time-offset-search S]
// A result folder's estimates.csv (and the dataset's ground truth) as TUM trajectory files, and
// each camera's absolute trajectory error against the truth or a reference.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"

namespace netvmo::tools {

void add_trajectories(CLI::App& app, int& exit_code) {
  struct Options {
    std::string results, dataset, out, reference;
    run::TrajectoryComparisonSettings compare;
    bool estimate_offset = false;
    run::TimeOffsetSettings offset;
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
      "With --dataset or --reference, every camera's absolute trajectory error against it\n"
      "(matched in time within --max-dt; with --align after a rigid alignment) is\n"
      "printed and written to OUT/comparison.json. --estimate-time-offset first finds the\n"
      "reference's time offset from the target's speeds (a reference on another clock).\n"
      "Written in OUT.partial-<pid> and swapped into place.");
  cmd->add_option("RESULTS", o->results, "result folder holding estimates.csv")->required();
  cmd->add_option("--dataset", o->dataset,
                  "the dataset the results were run on: also write its true target pose");
  cmd->add_option("--out", o->out, "output folder (default RESULTS/trajectories)");
  cmd->add_option("--reference", o->reference,
                  "a TUM file of the target's pose (e.g. from motion capture): compare every "
                  "camera with it instead of the dataset's truth");
  cmd->add_flag("--align", o->compare.align,
                "align each camera's trajectory onto the reference first (a rigid motion: the mean "
                "of the orientations' differences, then of the positions'), for a reference in "
                "another frame than the rig's world");
  cmd->add_option("--max-dt", o->compare.max_dt,
                  "[s] a pose is matched with the reference pose nearest in time within this")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--reference-time-offset", o->compare.reference_time_offset,
                  "[s] added to the reference's times to put them on the results' clock (for a "
                  "reference recorded on another clock)")
      ->capture_default_str();
  CLI::Option* estimate = cmd->add_flag(
      "--estimate-time-offset", o->estimate_offset,
      "estimate the reference's time offset (the --reference-time-offset at which the "
      "target's linear and angular speeds agree best over every camera's file, within "
      "--time-offset-search of --reference-time-offset) and compare at it");
  cmd->add_option("--time-offset-search", o->offset.search,
                  "[s] with --estimate-time-offset: the offsets tried lie within this of "
                  "--reference-time-offset")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->needs(estimate);
  cmd->callback([o, &exit_code]() {
    exit_code = guarded("trajectories", [&]() {
      const std::string out = o->out.empty() ? o->results + "/trajectories" : o->out;
      std::optional<std::filesystem::path> dataset;
      if (!o->dataset.empty()) {
        io::check_output_apart(out, o->dataset);
        dataset = o->dataset;
      }
      std::optional<std::filesystem::path> reference;
      if (!o->reference.empty()) reference = o->reference;
      if (!std::isfinite(o->compare.reference_time_offset))
        throw InputError(
            "--reference-time-offset: " + std::to_string(o->compare.reference_time_offset) +
            " s is not a finite number of seconds");
      if (!reference && o->compare.reference_time_offset != 0.0)
        throw InputError(
            "--reference-time-offset: needs --reference (the dataset's truth is on the results' "
            "clock)");
      if (!reference && o->estimate_offset)
        throw InputError(
            "--estimate-time-offset: needs --reference (the dataset's truth is on the results' "
            "clock)");
      if (!dataset && !reference && o->compare.align)
        throw InputError("--align: nothing to compare with (give --reference or --dataset)");
      io::OutputDir dir(out, "trajectories");
      const auto files = run::write_trajectories(o->results, dataset, dir.path());
      const auto done =
          run::write_comparisons(dir.path(), files, reference, o->compare,
                                 o->estimate_offset ? std::optional(o->offset) : std::nullopt);
      const auto& compared = done.cameras;
      dir.commit();
      std::printf("wrote %s:", out.c_str());
      for (const auto& f : files) std::printf(" %s (%zu poses)", f.name.c_str(), f.rows.size());
      std::printf("%s\n", files.empty() ? " nothing (no camera had an estimate)" : "");
      if (done.time_offset)
        std::printf(
            "reference time offset: %.4f s (the speeds' mismatch there %.3g, %.2f of its "
            "median over %zu offsets tried within %g s of %g s)\n",
            done.time_offset->offset, done.time_offset->mismatch,
            done.time_offset->mismatch / done.time_offset->median_mismatch,
            done.time_offset->offsets, o->offset.search, o->compare.reference_time_offset);
      if (!compared.empty())
        std::printf("absolute trajectory error%s (comparison.json):\n%-28s %8s %10s %10s %10s\n",
                    o->compare.align ? ", aligned" : "", "file", "matched", "pos_rmse_m",
                    "pos_max_m", "rot_rmse_deg");
      for (const auto& c : compared)
        std::printf("%-28s %8zu %10.4f %10.4f %10.3f\n", c.file.c_str(), c.comparison.matched,
                    c.comparison.position_rmse, c.comparison.position_max,
                    c.comparison.rotation_rmse * 180.0 / M_PI);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
