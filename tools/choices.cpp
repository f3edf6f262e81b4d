#include "choices.hpp"

#include <cstdint>
#include <cstdio>
#include <sstream>
#include <vector>

#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/estimator.hpp"
#include "netvmo/pipeline/sim/simulation.hpp"

namespace netvmo::tools {

CLI::Option* add_error_model_option(CLI::App& cmd, std::string& value, ErrorModelUse use) {
  std::vector<std::string> names;
  std::string help = "Visual error model of (eq:input_f-):";
  for (const auto* m : obs::error_models()) {
    const std::string name(m->name());
    if (use == ErrorModelUse::simulation && !sim::simulation_error_model_problem(name).empty())
      continue;
    names.push_back(name);
    help += "\n" + name + ": " + std::string(m->description());
  }
  return cmd.add_option("--error", value, help)->check(CLI::IsMember(names));
}

CLI::Option* add_estimator_option(CLI::App& cmd, std::string& value) {
  std::vector<std::string> names;
  std::string help = "Networked estimator:";
  for (const auto* e : obs::estimators()) {
    names.emplace_back(e->name());
    help += "\n" + names.back() + ": " + std::string(e->description());
  }
  return cmd.add_option("--estimator", value, help)->check(CLI::IsMember(names));
}

void add_transport_options(CLI::App& cmd, run::TransportSettings& s) {
  std::vector<std::string> names;
  std::string help = "How estimates travel between the cameras' observers:";
  for (const auto* k : run::transport_kinds()) {
    names.emplace_back(k->name());
    help += "\n" + names.back() + ": " + std::string(k->description());
  }
  cmd.add_option("--transport", s.kind, help)->check(CLI::IsMember(names))->capture_default_str();
  // Every kind's own parameters, as --<name> (once for a name two kinds share).
  for (const auto* k : run::transport_kinds())
    for (const auto& p : k->parameters()) {
      if (cmd.get_option_no_throw("--" + p.name)) continue;
      auto* o = cmd.add_option_function<double>(
          "--" + p.name, [&s, name = p.name](double v) { s.values[name] = v; }, p.help);
      const auto text = [&p](double v) {
        std::ostringstream t;
        if (p.integer)
          t << static_cast<std::uint64_t>(v);
        else
          t << v;
        return t.str();
      };
      const std::string range = "in [" + text(p.min) + ", " + text(p.max) + "]";
      o->check(CLI::Range(p.min, p.max).description(range))
          ->default_str(text(p.default_value))
          ->type_name(p.integer ? "UINT" : "FLOAT");
    }
}

void add_search_options(CLI::App& cmd, frontend::TrackingSettings& t) {
  cmd.add_flag_callback(
      "--no-track", [&t] { t.enabled = false; },
      "Search every frame whole at the detector's decimation (default: a window around the "
      "last detection first, the whole image when that fails and every 30 frames, and the "
      "full-resolution acquisition pass while the target is not seen)");
  cmd.add_option("--acquire-every", t.acquire_every,
                 "While a camera does not see the target, search every this many frames "
                 "again at full resolution for small tags (0: never)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd.add_option("--full-res-below", t.full_res_below_px,
                 "Search the tracking window at full resolution when the last tag's narrowest "
                 "side is below this [px] (0: never)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  cmd.add_option("--window-max-decimate", t.window_max_decimate,
                 "Search the tracking window decimated in proportion to the last tag's "
                 "narrowest side, up to this (the detector's decimation or less: never above it)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd.add_option("--change-pixels", t.change_pixels,
                 "A camera that does not see the target skips the whole-image search while fewer "
                 "than this many pixels changed by more than 24 gray levels (beyond a 1-pixel "
                 "shake) since its last such search; still searched every 30 frames (0: always "
                 "search)")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str();
  cmd.add_flag_callback(
      "--no-shadow-retry", [&t] { t.shadow_retry = false; },
      "No second search of the tracking window on a locally normalised copy (for tags "
      "crossed by a hard shadow edge) when the first fails");
}

std::vector<std::string> search_arguments(const frontend::TrackingSettings& t) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", t.full_res_below_px);
  std::vector<std::string> a = {"--acquire-every",       std::to_string(t.acquire_every),
                                "--full-res-below",      b,
                                "--window-max-decimate", std::to_string(t.window_max_decimate),
                                "--change-pixels",       std::to_string(t.change_pixels)};
  if (!t.enabled) a.push_back("--no-track");
  if (!t.shadow_retry) a.push_back("--no-shadow-retry");
  return a;
}

}  // namespace netvmo::tools
