// Fuzz target: estimates.csv as netvmo trajectories reads it (io::read_estimates_csv, any of its
// three headers), every pose read written back as a TUM line (run::tum_line).
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "estimates.csv");
  try {
    for (const auto& r : io::read_estimates_csv(path))
      if (r.g_w) (void)run::tum_line(r.t, *r.g_w);
  } catch (const InputError&) {
  }
  return 0;
}
