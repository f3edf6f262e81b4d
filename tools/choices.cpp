#include "choices.hpp"

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
    names.emplace_back(k->name);
    help += "\n" + std::string(k->name) + ": " + k->description;
  }
  cmd.add_option("--transport", s.kind, help)->check(CLI::IsMember(names))->capture_default_str();
  cmd.add_option("--drop", s.drop, "lossy transport: probability that a message is lost")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  cmd.add_option("--seed", s.seed, "lossy transport: seed of the losses")->capture_default_str();
}

}  // namespace netvmo::tools
