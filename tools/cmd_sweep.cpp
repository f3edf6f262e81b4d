// netvmo sweep: the observer over a grid of gains on one dataset, the front end run once (its
// outputs cached in OUT/inputs.csv and reused), measured epsilon-levels and final errors against
// k = k_e/k_s next to Theorem 1's guarantee.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/run/sweep.hpp"
#include "plot.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {

// The panels of sweep.png: with ground truth the measured eps-levels against g* next to
// Theorem 1's bound and the final errors; without it, what the measurements alone define (the
// eps-levels against the cameras' measured average, their disagreement, the last quarter's
// largest step). A series none of whose points is defined is left out (gnuplot refuses a plot
// whose points are all undefined), a panel without series too.
void plot_sweep(const fs::path& dir, std::string title, bool truth,
                const std::vector<run::SweepColumn>& columns) {
  for (size_t at = title.find('_'); at != std::string::npos; at = title.find('_', at + 2))
    title.insert(at, "\\");  // a literal underscore in gnuplot's enhanced text
  const fs::path csv = dir / "sweep.csv";
  const auto defined = [&](int y) {
    for (const auto& c : columns)
      if (c.index == y) return c.defined;
    return false;
  };
  const auto panel = [&](const char* title, const char* ylabel,
                         std::vector<std::tuple<const char*, int, const char*>> ser) {
    plot::Panel p{title, ylabel, true, {}, std::nullopt};
    for (const auto& [t, y, style] : ser)
      if (defined(y)) p.series.push_back(plot::Series{csv, t, y, 3, style, {}});
    p.xlabel = "k = k_e / k_s";
    p.log_x = true;
    return p;
  };
  std::vector<plot::Panel> panels;
  if (truth) {
    panels = {panel("positions", "{/Symbol e}_p",
                    {{"measured, last frame", 6, "linespoints pt 7 lw 2"},
                     {"measured, sup last quarter", 8, "linespoints pt 6 lw 1"},
                     {"Theorem 1 bound", 14, "lines dt 2 lw 2"}}),
              panel("orientations", "{/Symbol e}_R",
                    {{"measured, last frame", 7, "linespoints pt 7 lw 2"},
                     {"measured, sup last quarter", 9, "linespoints pt 6 lw 1"},
                     {"Theorem 1 bound", 15, "lines dt 2 lw 2"}}),
              panel("final error to g* (worst camera)", "mm, degrees",
                    {{"position [mm]", 12, "linespoints pt 7 lw 2"},
                     {"orientation [deg]", 13, "linespoints pt 5 lw 2"}})};
  } else {
    panels = {panel("{/Symbol e}-levels against the measured g* (PnP), last frame", "{/Symbol e}",
                    {{"{/Symbol e}_p", 16, "linespoints pt 7 lw 2"},
                     {"{/Symbol e}_R", 17, "linespoints pt 5 lw 2"}}),
              panel("disagreement between cameras, last frame", "mm, degrees",
                    {{"position [mm]", 18, "linespoints pt 7 lw 2"},
                     {"orientation [deg]", 19, "linespoints pt 5 lw 2"}}),
              panel("convergence: largest step in the last quarter", "mm, degrees per frame",
                    {{"position [mm]", 20, "linespoints pt 7 lw 2"},
                     {"orientation [deg]", 21, "linespoints pt 5 lw 2"}})};
  }
  panels.erase(std::remove_if(panels.begin(), panels.end(),
                              [](const plot::Panel& p) { return p.series.empty(); }),
               panels.end());
  if (panels.empty()) {
    std::printf("sweep.png: not drawn, no plotted quantity is defined at any grid point\n");
    return;
  }
  plot::panels_figure(panels, dir / "sweep.png", title);
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
      "settings reuses OUT/inputs.csv. Without ground truth (a recorded dataset) the columns\n"
      "against g* are nan and the sweep tabulates and plots what the measurements define: the\n"
      "eps-levels against the cameras' measured average, their disagreement and the last\n"
      "quarter's largest step. OUT is built in OUT.partial-<pid> and put in place at the end.");
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
      io::check_output_apart(o->out, o->dataset);
      auto source = sources::open_dataset_source(o->dataset);
      run::ImageRunSettings options;
      options.runner = o->runner;
      if (o->max_frames > 0) options.max_frames = o->max_frames;
      // Everything is written into the temporary out.path() and put in place at the end, so a
      // failure (e.g. of the plot) leaves OUT as it was. The front end's cache is read from OUT
      // (a previous sweep's) and written anew.
      io::OutputDir out(o->out, "sweep");
      const fs::path shown = o->out, dir = out.path();
      using Clock = std::chrono::steady_clock;
      auto t0 = Clock::now();
      auto inputs = run::read_inputs_cache(shown / "inputs.csv", *source, options);
      if (inputs) {
        std::printf("front end: reusing %s\n", (shown / "inputs.csv").string().c_str());
      } else {
        inputs = run::record_inputs(*source, options);
        std::printf("front end: %zu frames detected in %.1f s, cached in %s\n",
                    inputs->frames.size(), std::chrono::duration<double>(Clock::now() - t0).count(),
                    (shown / "inputs.csv").string().c_str());
      }
      run::write_inputs_cache(dir / "inputs.csv", *source, options, *inputs);
      const auto ctx = run::sweep_context(source->network(), *inputs);
      if (ctx.truth) {
        std::printf("graph: W = %g, diam = %d; last frame: |V_f| = %d, phi_m = %.3g\n", ctx.W,
                    ctx.diameter, ctx.n_visible, ctx.spread.phi_m);
        std::printf("%8s %8s %10s %6s %10s %10s %12s %12s\n", "k_e", "k_s", "k", "rounds", "eps_p",
                    "eps_R", "worst [mm]", "worst [deg]");
      } else {
        std::printf(
            "graph: W = %g, diam = %d; last frame: %d cameras with a PnP pose, measured phi_m = "
            "%.3g\n",
            ctx.W, ctx.diameter, ctx.n_measured, ctx.measured_spread.phi_m);
        std::printf("%8s %8s %10s %6s %10s %10s %12s %12s %12s %12s\n", "k_e", "k_s", "k", "rounds",
                    "eps_p~", "eps_R~", "apart [mm]", "apart [deg]", "step [mm]", "step [deg]");
      }
      t0 = Clock::now();
      std::vector<run::SweepPoint> points;
      for (double e : ke)
        for (double s : ks) {
          auto rs = o->runner;
          rs.k_e = e;
          rs.k_s = s;
          points.push_back(run::sweep_point(ctx, rs, *inputs));
          const auto& p = points.back();
          if (ctx.truth)
            std::printf("%8g %8g %10.4g %6d %10.3g %10.3g %12.2f %12.3f\n", e, s,
                        s > 0 ? e / s : INFINITY, p.rounds, p.eps_p, p.eps_R,
                        p.worst_position_m * 1000, p.worst_orientation_deg);
          else
            std::printf("%8g %8g %10.4g %6d %10.3g %10.3g %12.2f %12.3f %12.3f %12.4f\n", e, s,
                        s > 0 ? e / s : INFINITY, p.rounds, p.eps_p_measured, p.eps_R_measured,
                        p.disagreement_m * 1000, p.disagreement_deg, p.last_quarter_step_m * 1000,
                        p.last_quarter_step_deg);
          std::fflush(stdout);
        }
      const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
      const auto columns = run::sweep_columns(points);
      if (!ctx.truth) {
        std::string undefined;
        for (const auto& c : columns)
          if (!c.defined) undefined += (undefined.empty() ? "" : ", ") + std::string(c.name);
        std::printf(
            "no ground truth in %s (target.csv and truth_cameras.csv): undefined, nan in "
            "sweep.csv and not plotted: %s; eps_p~, eps_R~ are Definition 1's levels against the "
            "detecting cameras' measured average (eps_p_measured, eps_R_measured), apart the "
            "largest disagreement between two cameras (disagreement_mm, _deg), step the "
            "largest move of an estimate from one frame to the next in the last quarter "
            "(last_quarter_step_mm, _deg)\n",
            o->dataset.c_str(), undefined.c_str());
      }
      run::write_sweep_csv(dir / "sweep.csv", points);
      if (!o->no_plot) {
        try {
          plot_sweep(dir,
                     fs::path(o->dataset).filename().string() + ": " + o->runner.estimator +
                         ", error " + o->runner.error_model,
                     ctx.truth, columns);
        } catch (const std::runtime_error& e) {  // named as it would have been, under OUT
          std::string what = e.what();
          if (what.rfind(dir.string(), 0) == 0) what.replace(0, dir.string().size(), o->out);
          throw std::runtime_error(what);
        }
      }
      out.commit();
      std::printf("%zu grid points in %.2f s (observer only); results in %s/\n", points.size(),
                  secs, shown.string().c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
