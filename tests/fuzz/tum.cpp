// Fuzz target: a TUM trajectory file as netvmo trajectories reads a reference
// (run::read_tum), then compared with itself, unaligned and aligned
// (run::compare_trajectory), and its time offset to itself estimated (run::estimate_time_offset).
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "reference.txt");
  try {
    const auto rows = run::read_tum(path);
    run::TrajectoryComparisonSettings s;
    (void)run::compare_trajectory(rows, rows, s, "fuzz");
    s.align = true;
    (void)run::compare_trajectory(rows, rows, s, "fuzz");
    (void)run::estimate_time_offset(rows, {&rows}, s.max_dt, run::TimeOffsetSettings{}, "fuzz");
  } catch (const InputError&) {
  }
  return 0;
}
