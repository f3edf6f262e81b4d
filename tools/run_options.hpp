// Options shared by `netvmo run` and `netvmo demo`, and the run + report sequence.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::tools {

/// The command line's view of run::ImageRunSettings: every default is the library's own.
struct RunCliOptions {
  std::string estimator = run::RunnerSettings{}.estimator;
  std::vector<std::string> compare;  ///< --compare-estimator
  double k_e = run::RunnerSettings{}.k_e;
  double k_s = run::RunnerSettings{}.k_s;
  std::string error = run::RunnerSettings{}.error_model;
  std::string init = run::to_string(run::RunnerSettings{}.init);
  int rounds = run::RunnerSettings{}.rounds;
  bool keep_going = run::ImageRunSettings{}.keep_going;
  bool ignore_camera_velocity = run::ImageRunSettings{}.ignore_camera_velocity;
  bool no_overlays = false;
  bool no_plots = false;
  bool camera_videos = false;  ///< --camera-videos (run::OverlaySettings::camera_videos)
  bool progress = true;        ///< the progress bar on stderr
  int max_frames = 0;
  double decimate = frontend::DetectorSettings{}.quad_decimate;
  std::string refine = frontend::to_string(frontend::DetectorSettings{}.refinement);
  frontend::TrackingSettings tracking;
  run::TransportSettings transport;
  /// `run --calibration`: netvmo calibrate's calibration.json, whose covariances are propagated
  /// into g* in the summary (empty: none).
  std::string calibration;
};

/// Adds the options of `netvmo run`; `in_process_transport`: also --transport, --drop, --seed
/// (not for node and launch, whose transport is DDS with faults of their own).
void add_run_options(CLI::App& cmd, RunCliOptions& o, bool in_process_transport = true);
run::ImageRunSettings to_image_run_options(const RunCliOptions& o);
/// Runs the source, writes the outputs, overlays and plots into dir; returns the summary.
/// `shown`: the name dir will have when the command ends (dir is an io::OutputDir's temporary
/// folder), used instead of dir in the message of an error; empty: dir. `bag`: also write the
/// run as a rosbag2 bag into that (empty) folder (run::BagRecorder); empty: none.
nlohmann::json run_and_report(sources::NetworkSource& source, const RunCliOptions& o,
                              const std::filesystem::path& dir,
                              const std::filesystem::path& shown = {},
                              const std::filesystem::path& bag = {});

/// Prints the per-camera table of the summary.
void print_run_summary(const nlohmann::json& s, const std::filesystem::path& dir);

}  // namespace netvmo::tools
