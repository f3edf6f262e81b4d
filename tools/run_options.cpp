#include "run_options.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "choices.hpp"
#include "netvmo/observer/estimator.hpp"
#include "netvmo/pipeline/calib/g_star_uncertainty.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/run/bag_recorder.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "run_plots.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;
using nlohmann::json;

void add_run_options(CLI::App& cmd, RunCliOptions& o, bool in_process_transport) {
  add_estimator_option(cmd, o.estimator)->capture_default_str();
  if (in_process_transport) {
    std::vector<std::string> names;
    for (const auto* e : obs::estimators()) names.emplace_back(e->name());
    cmd.add_option("--compare-estimator", o.compare,
                   "Also run this networked estimator on the same measurements with the same "
                   "gains and report it in summary.json (cameras[].compared, final)")
        ->check(CLI::IsMember(names));
  }
  cmd.add_option("--ke", o.k_e,
                 "Visual feedback gain k_e > 0 (with --rounds 0 it sets the rounds: "
                 "k_e + 2 k_s d_max <= 10000 x fps)")
      ->capture_default_str();
  cmd.add_option("--ks", o.k_s, "Mutual feedback gain k_s >= 0 (0: independent observers)")
      ->capture_default_str();
  add_error_model_option(cmd, o.error, ErrorModelUse::images)->capture_default_str();
  cmd.add_option("--init", o.init,
                 "Initial estimates: pnp = first PnP pose, blind cameras from their neighbours; "
                 "paper = ([0,0,1], tag facing the camera)")
      ->check(CLI::IsMember({"pnp", "paper"}))
      ->capture_default_str();
  cmd.add_option("--rounds", o.rounds,
                 "Consensus (exchange) rounds per frame N, at most 10000; 0 = the smallest "
                 "stable count, h (k_e + 2 k_s d_max) <= 1 with h = 1 / (fps N)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd.add_flag("--keep-going", o.keep_going,
               "Treat a camera whose image cannot be read as blind for that frame, and one whose "
               "video cannot be opened (or stops decoding) as blind from then on, with a "
               "warning, instead of stopping (bad dataset files, e.g. timestamps.csv going "
               "backwards or repeating, still stop: no fallback guesses a clock)");
  cmd.add_flag("--no-overlays", o.no_overlays, "Do not write overlays/");
  cmd.add_flag("--camera-videos", o.camera_videos,
               "Also write overlays/cam_<id>.mp4, each camera's overlay at full resolution "
               "(default: the mosaic only)");
  cmd.add_flag("--no-plots", o.no_plots, "Do not draw energies.png and errors.png");
  cmd.add_option("--max-frames", o.max_frames, "Stop after this many frames (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--decimate", o.decimate, "libapriltag quad_decimate")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 8.0));
  add_search_options(cmd, o.tracking);
  if (in_process_transport) {
    add_transport_options(cmd, o.transport);
    cmd.add_flag("--ignore-camera-velocity", o.ignore_camera_velocity,
                 "Diagnostic for moving cameras (cameras.csv): keep each frame's believed poses "
                 "but set every camera body velocity V_wi of (eq:EsRRBM) to zero");
  }
  cmd.add_option("--refine", o.refine, "Corner refinement: none, subpix or edges")
      ->check(CLI::IsMember({"none", "subpix", "edges"}))
      ->capture_default_str();
}

run::ImageRunSettings to_image_run_options(const RunCliOptions& o) {
  if (!(o.k_e > 0) || !(o.k_s >= 0) || !std::isfinite(o.k_e) || !std::isfinite(o.k_s))
    throw InputError("--ke must be finite and > 0, --ks finite and >= 0");
  run::ImageRunSettings r;
  r.runner.estimator = o.estimator;
  r.runner.compare_estimators = o.compare;
  r.runner.k_e = o.k_e;
  r.runner.k_s = o.k_s;
  r.runner.error_model = o.error;
  r.runner.init = run::parse_init_mode(o.init);
  r.runner.rounds = o.rounds;
  r.keep_going = o.keep_going;
  r.progress = o.progress;
  r.ignore_camera_velocity = o.ignore_camera_velocity;
  if (o.max_frames > 0) r.max_frames = o.max_frames;
  r.detector.quad_decimate = o.decimate;
  r.detector.refinement = frontend::parse_refinement(o.refine);
  r.tracking = o.tracking;
  r.transport = o.transport;
  return r;
}

namespace {
json run_and_report_in(sources::NetworkSource& source, const RunCliOptions& o, const fs::path& dir,
                       const fs::path& bag_dir) {
  const auto options = to_image_run_options(o);
  std::map<int, Eigen::Matrix<double, 6, 6>> covariances;  // before the run: fail early
  if (!o.calibration.empty()) covariances = calib::read_calibration_covariances(o.calibration);
  for (const auto& w : source.warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  std::unique_ptr<run::OverlayWriter> overlays;
  run::FrameHook hook;
  if (!o.no_overlays) {
    run::OverlaySettings os;
    os.camera_videos = o.camera_videos;
    overlays = std::make_unique<run::OverlayWriter>(dir, source, os);
  }
  std::unique_ptr<run::BagRecorder> bag;
  if (!bag_dir.empty()) bag = std::make_unique<run::BagRecorder>(bag_dir, source);
  if (overlays || bag)
    hook = [&](int k, const std::vector<cv::Mat>& images,
               const std::vector<std::vector<frontend::Observation>>& cams,
               const std::vector<const run::FrameRecord*>& r) {
      if (overlays) (*overlays)(k, images, cams, r);
      if (bag) (*bag)(k, images, cams, r);
    };
  const auto result = run::run_images(source, options, hook);
  if (bag) bag->finish();
  for (size_t k = source.warnings().size(); k < result.warnings.size(); ++k)
    std::fprintf(stderr, "warning: %s\n", result.warnings[k].c_str());
  // Where the image times came from (a camera without timestamps.csv rows or video timestamps:
  // frame / fps), once the run has succeeded.
  for (const auto& note : source.notes()) std::fprintf(stderr, "note: %s\n", note.c_str());
  std::optional<json> localisation;
  if (!o.calibration.empty())
    localisation = calib::g_star_localisation_summary(source, result, covariances, o.calibration);
  json s = run::write_run_outputs(dir, source, options, result, localisation);
  if (!o.no_plots) plot_run(dir, source.network());
  // The overlays' writer thread has drawn on meanwhile.
  if (overlays) overlays->finish();
  return s;
}
}  // namespace

json run_and_report(sources::NetworkSource& source, const RunCliOptions& o, const fs::path& dir,
                    const fs::path& shown, const fs::path& bag) {
  // A file of dir named in a message (a plot or an overlay that cannot be written) is named as
  // it would have been under its final folder.
  const auto renamed = [&](std::string what) {
    if (!shown.empty() && what.rfind(dir.string(), 0) == 0)
      what.replace(0, dir.string().size(), shown.string());
    return what;
  };
  try {
    return run_and_report_in(source, o, dir, bag);
  } catch (const InputError& e) {
    throw InputError(renamed(e.what()));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(renamed(e.what()));
  }
}

namespace {
std::string cell(const json& stats, const char* key, double scale, const char* fmt) {
  if (stats.is_null()) return "-";
  char b[32];
  std::snprintf(b, sizeof b, fmt, stats[key].get<double>() * scale);
  return b;
}
}  // namespace

void print_run_summary(const json& s, const fs::path& dir) {
  std::printf(
      "%s: %d frames, %s, k_e = %g, k_s = %g, error %s, init %s, %d rounds/frame, %.1f network "
      "frames/s\n",
      s["dataset"].get<std::string>().c_str(), s["frames"].get<int>(),
      s["estimator"].get<std::string>().c_str(), s["k_e"].get<double>(), s["k_s"].get<double>(),
      s["error"].get<std::string>().c_str(), s["init"].get<std::string>().c_str(),
      s["rounds_per_frame"].get<int>(), s["timing"]["network_frames_per_second"].get<double>());
  // One block per target (a single target's keys are at the top level).
  const json blocks = s.contains("targets") ? s["targets"] : json::array({s});
  for (const auto& b : blocks) {
    if (blocks.size() > 1) std::printf("target %d:\n", b["target"].get<int>());
    const bool truth = !b["final"].is_null();
    std::printf("camera  seen   %s\n",
                truth ? "final error to g*: networked | independent | PnP   [mm, deg]"
                      : "(no ground truth: no errors)");
    for (const auto& c : b["cameras"]) {
      std::printf("%6d  %3.0f%%", c["id"].get<int>(), 100.0 * c["seen_fraction"].get<double>());
      if (truth) {
        for (const char* m : {"networked", "independent", "pnp"}) {
          const auto& st = c[m]["vs_g_star"];
          std::printf("   %7s %6s", cell(st, "final_position_m", 1000.0, "%.1f").c_str(),
                      cell(st, "final_orientation_deg", 1.0, "%.2f").c_str());
        }
      }
      std::printf("\n");
    }
    if (truth)
      std::printf("final U_p = %.3e, U_R = %.3e, eps_p = %.3g, eps_R = %.3g\n",
                  b["final"]["U_p"].get<double>(), b["final"]["U_R"].get<double>(),
                  b["final"]["eps_p"].get<double>(), b["final"]["eps_R"].get<double>());
  }
  if (s.contains("g_star_localisation") && s["g_star_localisation"].contains("final")) {
    const auto& f = s["g_star_localisation"]["final"];
    std::printf(
        "g* to the true target (target %d, last frame): %.1f mm, %.3f deg measured; "
        "localisation alone (calibration covariances, first order): %.1f mm, %.3f deg RMS\n",
        s.contains("targets") ? s["targets"][0]["target"].get<int>() : s.value("target", 0),
        1e3 * f["measured_position_m"].get<double>(), f["measured_orientation_deg"].get<double>(),
        1e3 * f["predicted_rms_position_m"].get<double>(),
        f["predicted_rms_orientation_deg"].get<double>());
  }
  std::printf("results in %s/\n", dir.string().c_str());
}

}  // namespace netvmo::tools
