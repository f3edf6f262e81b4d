// Fuzz target: simulation scenario YAML (sim::load_scenario, with its graph checks).
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/sim/simulation.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "scenario.yaml");
  try {
    const sim::SimScenario s = sim::load_scenario(path);
    (void)sim::simulation_error_model_problem(s.error_model);
  } catch (const InputError&) {
  }
  return 0;
}
