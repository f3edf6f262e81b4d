// netvmo simulate: the paper's Section 5 simulation from a scenario file.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/sim/simulation.hpp"
#include "plot.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {
constexpr double kMaxDuration = 3600.0;  ///< [s] of simulated time

struct SimulateOptions {
  std::string scenario;
  std::string out = "results/simulate";
  std::optional<double> k_e, k_s, duration, compare_ks;
  std::string error, estimator;
  bool no_plots = false;
};

std::string fmt3(const obs::Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "[%.4f, %.4f, %.4f]", v.x(), v.y(), v.z());
  return b;
}

std::string short_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

void make_plots(const sim::SimScenario& s, const sim::SimResult& r, const fs::path& dir,
                const std::optional<std::pair<double, fs::path>>& compare) {
  plot::Panel up{"position error energy U_p", "U_p [m^2]", true, {}, std::nullopt};
  plot::Panel ur{"orientation error energy U_R", "U_R", true, {}, std::nullopt};
  const std::string solid = "lines lw 2 lc rgb '#d62728'",
                    dashed = "lines lw 2 dt 2 lc rgb '#1f77b4'";
  up.series.push_back({dir / "energies.csv", "k_s = " + short_number(s.k_s), 2, 1, solid, {}});
  ur.series.push_back({dir / "energies.csv", "k_s = " + short_number(s.k_s), 3, 1, solid, {}});
  if (compare) {
    const fs::path c = compare->second / "energies.csv";
    up.series.push_back({c, "k_s = " + short_number(compare->first), 2, 1, dashed, {}});
    ur.series.push_back({c, "k_s = " + short_number(compare->first), 3, 1, dashed, {}});
  }
  plot::panels_figure(
      {up, ur}, dir / "energies.png",
      "Estimation error energies (" + s.error_model + " error, k_e = " + short_number(s.k_e) + ")");
  plot::Panel ori{"first element of ξ̄ sin θ̄ (world frame)",
                  "(ξ̄ sin θ̄)_x",
                  false,
                  {},
                  std::make_pair(std::string("average g*"), obs::e_R(r.g_star.linear()).x())};
  for (size_t i = 0; i < s.cameras.size(); ++i)
    ori.series.push_back({dir / "orientation_x.csv",
                          "camera " + std::to_string(s.cameras[i].id),
                          static_cast<int>(i) + 2,
                          1,
                          "lines lw 2",
                          {}});
  plot::panels_figure({ori}, dir / "orientation_x.png",
                      "Orientation estimates, k_s = " + short_number(s.k_s));
}
}  // namespace

void add_simulate(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = add_command(
      app, "simulate", "Run the observer on a simulation scenario (the paper's Section 5)",
      "Writes OUT/energies.csv (t,U_p,U_R), OUT/estimates.csv (t,camera,px,py,pz,rx,ry,rz),\n"
      "OUT/orientation_x.csv, OUT/summary.json, OUT/energies.png (Fig. 5) and\n"
      "OUT/orientation_x.png (Fig. 6).");
  cmd->add_option("SCENARIO", o->scenario, "Scenario YAML file (e.g. datasets/paper5.yaml)")
      ->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--ke", o->k_e, "Visual feedback gain k_e")->default_str("from scenario");
  cmd->add_option("--ks", o->k_s, "Mutual feedback gain k_s")->default_str("from scenario");
  cmd->add_option("--duration", o->duration, "Simulated time [s], at most 3600")
      ->default_str("from scenario");
  add_error_model_option(*cmd, o->error, ErrorModelUse::simulation)->default_str("from scenario");
  add_estimator_option(*cmd, o->estimator)->default_str("from scenario");
  cmd->add_option(
      "--compare-ks", o->compare_ks,
      "Also run with this k_s (into OUT/compare_ks) and draw it dashed in energies.png");
  cmd->add_flag("--no-plots", o->no_plots, "Skip the PNG plots");
  cmd->callback([o, &exit_code] {
    exit_code = guarded("simulate", [&] {
      auto s = sim::load_scenario(o->scenario);
      if (o->k_e) s.k_e = *o->k_e;
      if (o->k_s) s.k_s = *o->k_s;
      if (o->duration) s.duration = *o->duration;
      if (!o->error.empty()) {
        const std::string problem = sim::simulation_error_model_problem(o->error);
        if (!problem.empty()) throw InputError("--error: " + problem);
        s.error_model = o->error;
      }
      if (!o->estimator.empty()) s.estimator = o->estimator;
      if (!(s.duration > 0) || !(s.duration <= kMaxDuration))
        throw InputError("--duration " + std::to_string(s.duration) +
                         ": must be > 0 and at most 3600 s (every frame's estimates are kept "
                         "for the outputs)");
      {
        std::vector<int> degree(s.cameras.size(), 0);
        for (const auto& [a, b] : s.edges) ++degree.at(size_t(a)), ++degree.at(size_t(b));
        const int d_max = degree.empty() ? 0 : *std::max_element(degree.begin(), degree.end());
        run::checked_rounds(1.0 / s.fps, s.k_e, s.k_s, d_max, 0);  // gains: finite, not absurd
      }
      io::OutputDir out(o->out, "simulate");
      const fs::path dir = out.path();
      const auto r = sim::simulate(s);
      sim::write_outputs(s, r, dir);
      std::optional<std::pair<double, fs::path>> compare;
      if (o->compare_ks) {
        auto s2 = s;
        s2.k_s = *o->compare_ks;
        sim::write_outputs(s2, sim::simulate(s2), dir / "compare_ks");
        compare = std::make_pair(s2.k_s, dir / "compare_ks");
      }
      std::printf(
          "scenario %s: %zu cameras, %s, error %s, k_e = %g, k_s = %g, %d sub-steps/frame\n",
          s.name.c_str(), s.cameras.size(), s.estimator.c_str(), s.error_model.c_str(), s.k_e,
          s.k_s, r.substeps);
      std::printf("  g*: p* = %s  xi theta* = %s\n", fmt3(r.g_star.translation()).c_str(),
                  fmt3(obs::rotvec(r.g_star)).c_str());
      std::printf("  final: U_p = %.3e  U_R = %.3e  eps_p = %.3g  eps_R = %.3g\n",
                  r.energies.back().U_p, r.energies.back().U_R, r.eps_final.eps_p,
                  r.eps_final.eps_R);
      std::printf("  graph: W = %g (%s), diam = %d\n", r.W.value, r.W.exact ? "exact" : "bound",
                  r.diameter);
      if (!o->no_plots) make_plots(s, r, dir, compare);
      out.commit();
      std::printf("results in %s/\n", o->out.c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
