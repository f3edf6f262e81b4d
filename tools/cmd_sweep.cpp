// netvmo sweep: the observer over a grid of gains on one dataset, the front end run once (its
// outputs cached in OUT/inputs.csv and reused), measured epsilon-levels and final errors against
// k = k_e/k_s next to Theorem 1's guarantee.
#include <chrono>
#include <cstdio>
#include <memory>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/run/sweep.hpp"
#include "plot.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {

void plot_sweep(const fs::path& dir, std::string title) {
  for (size_t at = title.find('_'); at != std::string::npos; at = title.find('_', at + 2))
    title.insert(at, "\\");  // a literal underscore in gnuplot's enhanced text
  const fs::path csv = dir / "sweep.csv";
  const auto s = [&](const char* t, int y, const char* style) {
    return plot::Series{csv, t, y, 3, style, {}};
  };
  const auto panel = [](const char* title, const char* ylabel, std::vector<plot::Series> ser) {
    plot::Panel p{title, ylabel, true, std::move(ser), std::nullopt};
    p.xlabel = "k = k_e / k_s";
    p.log_x = true;
    return p;
  };
  plot::panels_figure({panel("positions", "{/Symbol e}_p",
                             {s("measured, last frame", 6, "linespoints pt 7 lw 2"),
                              s("measured, sup last quarter", 8, "linespoints pt 6 lw 1"),
                              s("Theorem 1 bound", 14, "lines dt 2 lw 2")}),
                       panel("orientations", "{/Symbol e}_R",
                             {s("measured, last frame", 7, "linespoints pt 7 lw 2"),
                              s("measured, sup last quarter", 9, "linespoints pt 6 lw 1"),
                              s("Theorem 1 bound", 15, "lines dt 2 lw 2")}),
                       panel("final error to g* (worst camera)", "mm, degrees",
                             {s("position [mm]", 12, "linespoints pt 7 lw 2"),
                              s("orientation [deg]", 13, "linespoints pt 5 lw 2")})},
                      dir / "sweep.png", title);
}

}  // namespace

void add_sweep(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/sweep", ks = "0,1,2,5,10,20,50,100", ke = "1";
    run::RunnerSettings runner;
    bool no_plot = false;
    int max_frames = 0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "sweep", "Run the observer over a grid of gains on one dataset (Theorem 1 on images)",
      "Writes OUT/sweep.csv (per grid point: rounds, measured eps_p, eps_R, energies, worst\n"
      "final error to g*, and Theorem 1's bound on eps_p, eps_R for k = k_e/k_s), OUT/sweep.png\n"
      "and OUT/inputs.csv: the front end's outputs (delta, corners, PnP pose per frame and\n"
      "camera). The front end runs once; a later sweep with the same OUT, dataset and detector\n"
      "settings reuses OUT/inputs.csv.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder (netvmo render output or recorded)")
      ->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--ks", o->ks, "Mutual feedback gains k_s, comma-separated (>= 0)")
      ->capture_default_str();
  cmd->add_option("--ke", o->ke, "Visual feedback gains k_e, comma-separated (> 0)")
      ->capture_default_str();
  add_estimator_option(*cmd, o->runner.estimator)->capture_default_str();
  add_error_model_option(*cmd, o->runner.error_model, ErrorModelUse::images)->capture_default_str();
  cmd->add_option("--rounds", o->runner.rounds,
                  "Exchange rounds per frame; 0 = the smallest stable count for each point")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-frames", o->max_frames, "Use only the first frames (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-plot", o->no_plot, "Do not draw sweep.png");
  cmd->callback([o, &exit_code] {
    exit_code = guarded("sweep", [&] {
      const auto ks = run::parse_gain_list("--ks", o->ks, true);
      const auto ke = run::parse_gain_list("--ke", o->ke, false);
      // An estimator that cannot run with this error model fails here, before any detection.
      obs::CameraObserver(0, {}, run::camera_observer_settings(o->runner, false), 1);
      auto provider = sources::open_dataset_source(o->dataset);
      run::ImageRunOptions options;
      options.runner = o->runner;
      if (o->max_frames > 0) options.max_frames = o->max_frames;
      const fs::path dir = o->out, cache = dir / "inputs.csv";
      io::ensure_directory(dir);
      using Clock = std::chrono::steady_clock;
      auto t0 = Clock::now();
      auto inputs = run::read_inputs_cache(cache, *provider, options);
      if (inputs) {
        std::printf("front end: reusing %s\n", cache.string().c_str());
      } else {
        inputs = run::record_inputs(*provider, options);
        run::write_inputs_cache(cache, *provider, options, *inputs);
        std::printf("front end: %zu frames detected in %.1f s, cached in %s\n",
                    inputs->frames.size(), std::chrono::duration<double>(Clock::now() - t0).count(),
                    cache.string().c_str());
      }
      const auto ctx = run::sweep_context(provider->network(), *inputs);
      std::printf("graph: W = %g, diam = %d; last frame: |V_f| = %d, phi_m = %.3g\n", ctx.W,
                  ctx.diameter, ctx.n_visible, ctx.spread.phi_m);
      std::printf("%8s %8s %10s %6s %10s %10s %12s %12s\n", "k_e", "k_s", "k", "rounds", "eps_p",
                  "eps_R", "worst [mm]", "worst [deg]");
      t0 = Clock::now();
      std::vector<run::SweepPoint> points;
      for (double e : ke)
        for (double s : ks) {
          auto rs = o->runner;
          rs.k_e = e;
          rs.k_s = s;
          points.push_back(run::sweep_point(ctx, rs, *inputs));
          const auto& p = points.back();
          std::printf("%8g %8g %10.4g %6d %10.3g %10.3g %12.2f %12.3f\n", e, s,
                      s > 0 ? e / s : INFINITY, p.rounds, p.eps_p, p.eps_R,
                      p.worst_position_m * 1000, p.worst_orientation_deg);
          std::fflush(stdout);
        }
      const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
      run::write_sweep_csv(dir / "sweep.csv", points);
      if (!o->no_plot)
        plot_sweep(dir, fs::path(o->dataset).filename().string() + ": " + o->runner.estimator +
                            ", error " + o->runner.error_model);
      std::printf("%zu grid points in %.2f s (observer only); results in %s/\n", points.size(),
                  secs, dir.string().c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
