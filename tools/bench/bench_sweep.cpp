// A 20-point gain sweep (k_e in {1, 10} x k_s in {0, 1, 2, 5, 10, 20, 50, 100, 200, 500}) of
// paper5_render (150 frames, 5 cameras) after the one front-end pass: only the observer runs per
// point, as in `netvmo sweep`. The front-end pass (live rendering + detection + PnP) is done once
// before timing and printed as the counter front_end_s.
#include <benchmark/benchmark.h>

#include <chrono>

#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/run/sweep.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"

using namespace netvmo;

namespace {
void BM_Sweep20Points(benchmark::State& state) {
  auto source = sources::make_render_source(
      io::load_render_scenario(std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5_render.yaml"),
      150);
  run::ImageRunSettings o;
  o.progress = false;
  const auto t0 = std::chrono::steady_clock::now();
  const auto inputs = run::record_inputs(*source, o);
  const double front_end =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto ctx = run::sweep_context(source->network(), inputs);
  int points = 0;
  for (auto _ : state) {
    for (double k_e : {1.0, 10.0})
      for (double k_s : {0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0}) {
        run::RunnerSettings rs;
        rs.k_e = k_e;
        rs.k_s = k_s;
        benchmark::DoNotOptimize(run::sweep_point(ctx, rs, inputs));
        ++points;
      }
  }
  state.counters["front_end_s"] = front_end;
  state.counters["frames"] = static_cast<double>(inputs.frames.size());
  state.counters["points"] = 20;
}
BENCHMARK(BM_Sweep20Points)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);
}  // namespace

BENCHMARK_MAIN();
