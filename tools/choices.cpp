#include "choices.hpp"

#include <vector>

#include "netvmo/observer/error_model.hpp"
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

}  // namespace netvmo::tools
