// netvmo bench: network frames per second of the whole pipeline, on recorded data (decode +
// detection + observer) and on live rendering (render + detection + observer).
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"
#include "netvmo/render/renderer.hpp"
#include "run_options.hpp"
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
// Resident memory of this process [kB] (VmRSS of /proc/self/status), or -1.
long vm_rss_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  return -1;
}

// A source that plays another one's frames over and over (frame k is frame k mod n).
class LoopSource final : public sources::NetworkSource {
 public:
  LoopSource(std::unique_ptr<sources::NetworkSource> inner, int frames)
      : inner_(std::move(inner)), frames_(frames), n_(inner_->frame_count()) {}
  const io::NetworkConfig& network() const override { return inner_->network(); }
  const io::Calibration& calibration(size_t i) const override { return inner_->calibration(i); }
  int frame_count() const override { return frames_; }
  bool one_frame_at_a_time() const override { return inner_->one_frame_at_a_time(); }
  cv::Mat read(size_t i, int frame) override { return inner_->read(i, frame % n_); }
  std::optional<obs::SE3> target_truth(int frame, size_t target) const override {
    return inner_->target_truth(frame % n_, target);
  }
  std::optional<obs::SE3> camera_truth(size_t i, int frame) const override {
    return inner_->camera_truth(i, frame % n_);
  }
  obs::SE3 camera_believed(size_t i, int frame) const override {
    return inner_->camera_believed(i, frame % n_);
  }
  bool cameras_move() const override { return inner_->cameras_move(); }
  std::string name() const override { return inner_->name() + " (looped)"; }

 private:
  std::unique_ptr<sources::NetworkSource> inner_;
  int frames_, n_;
};

// The soak: `source` (a looped recorded dataset, or live rendering) -> front end -> networked
// observer for its frames, keeping no per-frame history; every `every` frames one row of
// `frames seconds ms_per_frame vmrss_kb` (ms per frame over the last `every` frames) is
// appended to `log` and flushed, so a partial run is usable.
void soak(sources::NetworkSource& source, const std::string& what, int every, const fs::path& log) {
  std::ofstream out(log);
  if (!out) throw InputError(log.string() + ": cannot open for writing");
  out << "# netvmo bench --soak: " << what << ", " << source.network().cameras.size()
      << " cameras, in-process networked observer, " << source.frame_count() << " frames\n"
      << "# frames seconds ms_per_frame vmrss_kb\n";
  run::ImageRunSettings run;
  run.progress = false;
  run.runner.keep_history = false;
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0;
  const auto hook = [&](int k, const std::vector<cv::Mat>&,
                        const std::vector<std::vector<frontend::Observation>>&,
                        const std::vector<const run::FrameRecord*>&) {
    if ((k + 1) % every != 0) return;
    const auto now = std::chrono::steady_clock::now();
    const double total = std::chrono::duration<double>(now - t0).count();
    const double ms = 1000.0 * std::chrono::duration<double>(now - last).count() / every;
    last = now;
    char row[128];
    std::snprintf(row, sizeof row, "%d %.3f %.3f %ld\n", k + 1, total, ms, vm_rss_kb());
    out << row << std::flush;
    std::fputs(row, stdout);
    std::fflush(stdout);
  };
  run::run_images(source, run, hook);
}
// A recording played through the whole `netvmo run` pipeline, looped to `frames` network
// frames, `repeat` times each way, alternately: bare (--no-overlays --no-plots: the CSVs and
// summary only) and with the default outputs (overlays, plots). Each figure is wall time from
// the first image read to the last output written; the split comes from the run's own timers.
// The anchor, measured in the same run: reading (decoding) the same images alone on as many
// threads as the run's front end, the most any pipeline could do with this decoder here.
void recording(const fs::path& dir, int frames, int repeat) {
  auto inner = sources::open_dataset_source(dir);
  const size_t n = inner->network().cameras.size();
  LoopSource looped(std::move(inner), frames);
  int width = 0, height = 0;
  for (size_t i = 0; i < n; ++i) {
    width = std::max(width, looped.calibration(i).width);
    height = std::max(height, looped.calibration(i).height);
  }
  std::printf(
      "recording %s: %zu cameras, up to %dx%d, looped to %d network frames, %d times each "
      "way\n",
      dir.string().c_str(), n, width, height, frames, repeat);
  const fs::path out =
      fs::temp_directory_path() / ("netvmo_bench_out_" + std::to_string(::getpid()));
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const int workers = run::ImageRunSettings{}.workers;
  std::vector<double> reading_only, wall[2];
  std::vector<nlohmann::json> timing[2];
  for (int r = 0; r < repeat; ++r) {
    {  // the anchor
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<std::thread> threads;
      for (int w = 0; w < workers; ++w)
        threads.emplace_back([&, w] {
          for (int k = 0; k < frames; ++k)
            for (size_t i = static_cast<size_t>(w); i < n; i += static_cast<size_t>(workers))
              looped.read(i, k);
        });
      for (auto& t : threads) t.join();
      reading_only.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    for (const int outputs : {0, 1}) {
      RunCliOptions o;
      o.no_overlays = o.no_plots = !outputs;
      o.progress = false;
      fs::remove_all(out);
      fs::create_directories(out);
      const auto t0 = std::chrono::steady_clock::now();
      const auto summary = run_and_report(looped, o, out, {});
      wall[outputs].push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      timing[outputs].push_back(summary["timing"]);
    }
  }
  fs::remove_all(out);
  std::printf("%-16s %6.1f network frames/s  (the anchor: reading alone, %d threads)\n",
              "reading only", frames / median(reading_only), workers);
  for (const int outputs : {0, 1}) {
    const auto ms = [&](const char* key) {
      std::vector<double> v;
      for (const auto& t : timing[outputs]) v.push_back(t[key].get<double>());
      return 1000.0 * median(v) / frames;
    };
    const double s = median(wall[outputs]);
    std::printf(
        "%-16s %6.1f network frames/s  (median of %d; per network frame: %.2f ms waiting for the "
        "front end, %.2f ms observer, %.2f ms the rest: outputs)\n",
        outputs ? "default outputs" : "bare", frames / s, repeat, ms("front_end_seconds"),
        ms("observer_seconds"),
        1000.0 * s / frames - ms("front_end_seconds") - ms("observer_seconds"));
    std::printf(
        "%-16s front end, summed over its threads, per network frame: reading (decoding) %.2f "
        "ms, search (libapriltag) %.2f ms, refinement %.2f ms, check %.2f ms\n",
        "", ms("reading_seconds"), ms("search_seconds"), ms("refinement_seconds"),
        ms("check_seconds"));
  }
  std::printf("the default outputs cost %.0f %% on top of bare\n",
              100.0 * (median(wall[1]) / median(wall[0]) - 1.0));
}
}  // namespace

void add_bench(CLI::App& app, int& exit_code) {
  struct Options {
    std::string scenario = "datasets/paper5_render.yaml";
    std::string moving = "datasets/moving_target.yaml";
    std::string targets = "datasets/two_targets.yaml";
    int frames = 60;
    int live_spp = 1;
    int soak = 0, soak_every = 1000;
    std::string soak_log = "soak.dat", soak_source = "recorded";
    std::string recording;
    int repeat = 3;
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
  cmd->add_option("--targets-scenario", o->targets,
                  "Scenario with several targets, one carrying a tag bundle (recorded: every "
                  "target decided in one front-end pass, one networked observer per target)")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames per measurement (1 to 100000)")
      ->capture_default_str()
      ->check(CLI::Range(1, io::kMaxDatasetFrames));
  cmd->add_option("--live-spp", o->live_spp, "Samples per pixel for live rendering (1 to 1024)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--soak", o->soak,
                  "Instead: the soak, N network frames of --scenario through the front end and "
                  "the networked observer, no history kept (tools/soak.sh)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000000));
  cmd->add_option("--soak-every", o->soak_every, "Soak: a row every this many frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--soak-source", o->soak_source,
                  "Soak: recorded (a --frames render of --scenario, played in a loop: "
                  "PNG decoding) or live (rendered every frame; static scenes reuse the radiance)")
      ->check(CLI::IsMember({"recorded", "live"}))
      ->capture_default_str();
  cmd->add_option("--soak-log", o->soak_log,
                  "Soak: table of frames, seconds, ms per frame, VmRSS [kB]")
      ->capture_default_str();
  cmd->add_option("--recording", o->recording,
                  "Instead: a recorded dataset folder through `netvmo run`, looped to --frames, "
                  "bare (--no-overlays --no-plots) and with the default outputs")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--repeat", o->repeat, "--recording: runs each way (the median is printed)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->callback([o, &exit_code] {
    exit_code = guarded("bench", [&] {
      if (!o->recording.empty()) {
        recording(o->recording, o->frames, o->repeat);
        return 0;
      }
      const fs::path scenario = find_scenario(o->scenario);
      const auto scene = io::load_render_scenario(scenario);
      if (o->soak > 0 && o->soak_source == "live") {
        auto live_scene = scene;
        live_scene.imaging.spp = o->live_spp;
        auto live = sources::make_render_source(live_scene, o->soak);
        soak(*live, "live rendering of " + scenario.string(), o->soak_every, o->soak_log);
        return 0;
      }
      run::ImageRunSettings run;
      run.progress = false;
      run.max_frames = o->frames;
      // Recorded: render a dataset first (not timed), then decode + detect + observe.
      const fs::path tmp =
          fs::temp_directory_path() / ("netvmo_bench_" + std::to_string(::getpid()));
      const auto render_dataset = [&](const render::SceneDescription& sc, const fs::path& from) {
        render::Renderer renderer(sc);
        io::DatasetSettings d;
        d.frames = o->frames;
        d.progress = false;
        std::printf("rendering %d frames of %s for the recorded measurement...\n", o->frames,
                    from.string().c_str());
        io::write_dataset(renderer, tmp, d);
      };
      render_dataset(scene, scenario);
      if (o->soak > 0) {  // recorded: the dataset just rendered (o->frames), looped
        LoopSource looped(sources::open_dataset_source(tmp), o->soak);
        soak(looped, std::to_string(o->frames) + " frames of " + scenario.string() + " looped",
             o->soak_every, o->soak_log);
        fs::remove_all(tmp);
        return 0;
      }
      auto recorded = sources::open_dataset_source(tmp);
      const auto r1 = run::run_images(*recorded, run);
      report("recorded (PNG decode+detect+observe)", r1, scene.cameras.size());
      fs::remove_all(tmp);
      {
        const fs::path targets_file = find_scenario(o->targets);
        const auto targets_scene = io::load_render_scenario(targets_file);
        render_dataset(targets_scene, targets_file);
        auto two = sources::open_dataset_source(tmp);
        const auto r = run::run_images(*two, run);
        char what[64];
        std::snprintf(what, sizeof what, "recorded, %zu targets (bundle)",
                      two->network().targets.size());
        report(what, r, targets_scene.cameras.size());
        fs::remove_all(tmp);
      }
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
