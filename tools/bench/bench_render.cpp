// Renderer speed on datasets/paper5_render.yaml (640x480): ms per frame and primary rays per
// second at 1 and 4 samples per pixel, tile-parallel over all cores with Embree ray packets and
// shading (texture, ambient + directional light with shadow rays, noise); compared with a bare
// one-ray-at-a-time rtcIntersect1 loop over the same primary rays with no shading.
#include <benchmark/benchmark.h>

#include <memory>
#include <thread>

#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"

namespace {

using netvmo::render::Renderer;

std::unique_ptr<Renderer> make_renderer(int spp, bool shadows = true, bool textures = true) {
  auto scene = netvmo::io::load_render_scenario(NETVMO_SOURCE_DIR "/datasets/paper5_render.yaml");
  scene.imaging.spp = spp;
  scene.imaging.reuse_static = false;  // measure tracing, not the static-scene reuse
  for (auto& l : scene.lights) l.shadows = shadows;
  if (!textures) {
    for (auto& b : scene.occluders)
      for (auto& sh : b.shapes) sh.material.pattern = netvmo::render::Material::Pattern::Solid;
    for (auto& sh : scene.target.shapes)
      sh.material.pattern = netvmo::render::Material::Pattern::Solid;
  }
  return std::make_unique<Renderer>(scene);
}

// Camera 1 (index 0) sees the target; arg 0 = spp.
void BM_RenderFrame(benchmark::State& state) {
  const int spp = int(state.range(0));
  auto r = make_renderer(spp);
  const int cam = int(state.range(1));
  r->render(cam, 0);
  for (auto _ : state) {
    cv::Mat img = r->render(cam, 0);
    benchmark::DoNotOptimize(img.data);
  }
  const double rays = double(640 * 480) * spp;
  state.counters["primary_rays/s"] =
      benchmark::Counter(rays * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["threads"] = std::thread::hardware_concurrency();
}
BENCHMARK(BM_RenderFrame)
    ->ArgsProduct({{1, 4}, {0, 4}})
    ->ArgNames({"spp", "cam"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Cost breakdown: the same frame without shadow rays, and without shadows or procedural
// textures (solid albedo; the tag texture stays).
void BM_RenderFrameNoShadows(benchmark::State& state) {
  const int spp = int(state.range(0));
  auto r = make_renderer(spp, false, state.range(1) != 0);
  r->render(0, 0);
  for (auto _ : state) {
    cv::Mat img = r->render(0, 0);
    benchmark::DoNotOptimize(img.data);
  }
  state.counters["primary_rays/s"] = benchmark::Counter(
      double(640 * 480) * spp * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrameNoShadows)
    ->ArgsProduct({{1, 4}, {1, 0}})
    ->ArgNames({"spp", "textures"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Bare rtcIntersect1 loop, no shading, over `threads` threads.
void BM_BareIntersect1(benchmark::State& state) {
  const int spp = int(state.range(0));
  const int threads = int(state.range(2));
  auto r = make_renderer(spp);
  const int cam = int(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(r->intersect_bare(cam, 0, threads));
  const double rays = double(640 * 480) * spp;
  state.counters["primary_rays/s"] =
      benchmark::Counter(rays * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BareIntersect1)
    ->ArgsProduct({{1, 4}, {0, 4}, {1, 2}})
    ->ArgNames({"spp", "cam", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Ground truth for one camera and frame (corners + 16x16 visibility rays).
void BM_Truth(benchmark::State& state) {
  auto r = make_renderer(1);
  for (auto _ : state) benchmark::DoNotOptimize(r->truth(0, 0).visible_fraction);
}
BENCHMARK(BM_Truth)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
