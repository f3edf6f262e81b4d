// Options shared by `netvmo run` and `netvmo demo`, and the run + report sequence.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "netvmo/pipeline/sources/network_source.hpp"
#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::tools {

struct RunCliOptions {
  double k_e = 1.0;
  double k_s = 50.0;
  std::string error = "pnp";
  std::string init = "pnp";
  int rounds = 0;
  bool keep_going = false;
  bool no_overlays = false;
  bool no_plots = false;
  int max_frames = 0;
  double decimate = 2.0;
  std::string refine = "edges";
  bool no_track = false;
};

void add_run_options(CLI::App& cmd, RunCliOptions& o);
run::ImageRunOptions to_image_run_options(const RunCliOptions& o);

/// Runs the provider, writes the outputs, overlays and plots into dir; returns the summary.
nlohmann::json run_and_report(sources::NetworkSource& provider, const RunCliOptions& o,
                              const std::filesystem::path& dir);

/// Prints the per-camera table of the summary.
void print_run_summary(const nlohmann::json& s, const std::filesystem::path& dir);

}  // namespace netvmo::tools
