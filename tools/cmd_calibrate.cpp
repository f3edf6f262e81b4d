// netvmo calibrate: every camera's pose from tags (a map of static tags, or a tag moved through
// the rig), written as a network.yaml that `run` takes, with the covariances (calibrate.hpp).
#include <cstdio>
#include <memory>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/calib/calibrate.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "plot.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {

// Residuals of every camera against the frame, and du against dv.
void plot_residuals(const fs::path& dir, const calib::CalibrationResult& r) {
  for (const auto& c : r.cameras) {
    if (c.residuals.empty()) continue;
    const std::string id = std::to_string(c.id);
    const fs::path csv = dir / ("residuals_cam_" + id + ".csv");
    const std::string pts = "points pt 7 ps 0.4";
    plot::Panel time{"corner residuals (used)", "[undistorted px]", false, {}, {}, "frame"};
    time.series.push_back({csv, "du", 4, 1, pts, std::make_pair(6, 1.0)});
    time.series.push_back({csv, "dv", 5, 1, pts, std::make_pair(6, 1.0)});
    plot::Panel scatter{"du against dv", "dv [px]", false, {}, {}, "du [px]"};
    scatter.series.push_back({csv, "used", 5, 4, pts, std::make_pair(6, 1.0)});
    scatter.series.push_back({csv, "rejected", 5, 4, pts, std::make_pair(6, 0.0)});
    plot::panels_figure({time, scatter}, dir / ("residuals_cam_" + id + ".png"),
                        "camera " + id + ": reprojection residuals");
  }
}

}  // namespace

void add_calibrate(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/calibrate", map;
    int reference = 0;
    bool reference_identity = false;
    std::vector<int> tags;
    bool keep_going = false, no_plots = false;
    int max_frames = 0;
    double decimate = frontend::DetectorSettings{}.quad_decimate;
    double huber = calib::CalibrationSettings{}.huber_px;
    frontend::TrackingSettings tracking;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "calibrate", "Estimate every camera's pose from tags (a map, or a moved tag)",
      "Writes OUT/network.yaml (the dataset's, every camera's pose estimated; run takes it as\n"
      "it is: copy it, and OUT/cameras.csv when written, into the dataset folder or a copy),\n"
      "OUT/calibration.json (per camera: observations used and rejected, reprojection RMS,\n"
      "pose standard deviations and covariance), OUT/residuals_cam_<id>.csv and .png, and a\n"
      "line per camera on stdout. With --map: each camera from the map's static tags over all\n"
      "its frames. Without: a tag (network.yaml's target and bundle) moved through the rig,\n"
      "cameras and tag poses estimated jointly, the reference camera held fixed. A camera that\n"
      "cannot be calibrated stops the command, or with --keep-going is left out. Model and\n"
      "accuracy: docs/calibration.md.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder (netvmo render output or recorded)")
      ->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--map", o->map,
                  "MAP.yaml: the static tags' world poses (tags: [{family, id, size, p, r}])");
  cmd->add_option("--reference-camera", o->reference,
                  "Without a map: the camera held fixed (default: network.yaml's first)");
  cmd->add_flag("--reference-at-identity", o->reference_identity,
                "Without a map: hold the reference camera at the identity (default: at its "
                "network.yaml pose)");
  cmd->add_option("--tags", o->tags, "Use only these tag ids (comma separated)")->delimiter(',');
  cmd->add_flag("--keep-going", o->keep_going,
                "Leave a camera that cannot be calibrated out of network.yaml (and its edges) "
                "instead of stopping");
  cmd->add_flag("--no-plots", o->no_plots, "Do not draw residuals_cam_<id>.png");
  cmd->add_option("--max-frames", o->max_frames, "Use only the first frames (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--decimate", o->decimate, "libapriltag quad_decimate")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 8.0));
  cmd->add_option("--huber", o->huber, "Huber loss scale [px]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  add_search_options(*cmd, o->tracking);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("calibrate", [&] {
      std::optional<calib::TagMap> map;
      if (!o->map.empty()) map = calib::load_tag_map(o->map);
      io::check_output_apart(o->out, o->dataset);
      auto ds = sources::open_dataset(o->dataset, {}, o->keep_going);
      for (const auto& w : ds.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
      calib::CalibrationSettings s;
      s.detector.quad_decimate = o->decimate;
      s.tracking = o->tracking;
      s.huber_px = o->huber;
      s.tags = o->tags;
      s.reference_camera = o->reference;
      s.reference_from_network = !o->reference_identity;
      s.max_frames = o->max_frames;
      const auto result = calib::calibrate(ds, map, s);
      for (const auto& c : result.cameras) std::printf("%s\n", calib::camera_line(c).c_str());
      std::fflush(stdout);
      const auto net = calib::calibrated_network(ds.network, result, o->keep_going);
      io::OutputDir out(o->out, "calibrate");
      calib::write_calibration(out.path(), ds, result, net);
      if (!o->no_plots) plot_residuals(out.path(), result);
      out.commit();
      std::printf("wrote %s/network.yaml and calibration.json\n", o->out.c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
