// Renderer speed on datasets/paper5_render.yaml (640x480): ms per frame and primary rays per
// second at 1 and 4 samples per pixel, tile-parallel over all cores with Embree ray packets and
// shading (texture, ambient + directional light with shadow rays, noise); compared with a bare
// one-ray-at-a-time rtcIntersect1 loop over the same primary rays with no shading; the same on
// the moving scene datasets/moving_target.yaml, with and without radiance reuse; grid against
// jittered pixel sampling at 9 samples per pixel.
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
  scene.imaging.reuse_radiance = false;  // measure tracing, not the radiance reuse
  for (auto& l : scene.lights) l.shadows = shadows;
  if (!textures) {
    for (auto& b : scene.occluders)
      for (auto& sh : b.shapes) sh.material.pattern = netvmo::render::Material::Pattern::Solid;
    for (auto& sh : scene.target().shapes)
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

// Pixel sampling (imaging.sampling): the same frame at 9 samples per pixel with the grid pattern
// (arg 0, the anchor) and jittered per pixel (arg 1); camera 1 (index 0) is a pinhole camera,
// camera 2 (index 1) has lens distortion (its rays come from the per-camera table).
void BM_RenderFrameSampling(benchmark::State& state) {
  auto scene = netvmo::io::load_render_scenario(NETVMO_SOURCE_DIR "/datasets/paper5_render.yaml");
  scene.imaging.spp = 9;
  scene.imaging.reuse_radiance = false;
  scene.imaging.sampling = state.range(0) ? netvmo::render::Imaging::Sampling::Jittered
                                          : netvmo::render::Imaging::Sampling::Grid;
  Renderer r(scene);
  const int cam = int(state.range(1));
  r.render(cam, 0);
  for (auto _ : state) {
    cv::Mat img = r.render(cam, 0);
    benchmark::DoNotOptimize(img.data);
  }
  state.counters["primary_rays/s"] = benchmark::Counter(
      double(640 * 480) * 9 * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrameSampling)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->ArgNames({"jittered", "cam"})
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

// Moving scene (datasets/moving_target.yaml, 1 spp, 640x480): one iteration renders the five
// cameras' images of the next frame, frames 1..59 (a forth-and-back sweep when repeated), with
// the radiance
// reused where no moved body or its shadow can reach (arg 1) or traced in full (arg 0).
std::unique_ptr<Renderer> make_moving_renderer(bool reuse) {
  auto scene = netvmo::io::load_render_scenario(NETVMO_SOURCE_DIR "/datasets/moving_target.yaml");
  scene.imaging.spp = 1;
  scene.imaging.reuse_radiance = reuse;
  return std::make_unique<Renderer>(scene);
}

constexpr int kMovingFrames = 60;

// Frame of step i of a forth-and-back sweep over 0..kMovingFrames-1.
int sweep_frame(long i) {
  const long period = 2 * (kMovingFrames - 1), k = i % period;
  return int(k < kMovingFrames ? k : period - k);
}

void BM_RenderMovingScene(benchmark::State& state) {
  auto r = make_moving_renderer(state.range(0) != 0);
  for (int c = 0; c < r->camera_count(); ++c) r->render(c, 0);
  long step = 1;
  double traced = 0;
  for (auto _ : state) {
    const int frame = sweep_frame(step++);
    for (int c = 0; c < r->camera_count(); ++c) {
      cv::Mat img = r->render(c, frame);
      benchmark::DoNotOptimize(img.data);
      traced += r->traced_fraction(c);
    }
  }
  const double images = double(state.iterations()) * r->camera_count();
  state.counters["images/s"] = benchmark::Counter(images, benchmark::Counter::kIsRate);
  state.counters["traced_fraction"] = traced / images;
}
BENCHMARK(BM_RenderMovingScene)
    ->Arg(1)
    ->Arg(0)
    ->ArgName("reuse")
    ->Iterations(kMovingFrames - 1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The bare rtcIntersect1 loop over the same five cameras and frames, 2 threads.
void BM_BareIntersect1MovingScene(benchmark::State& state) {
  auto r = make_moving_renderer(false);
  long step = 1;
  for (auto _ : state) {
    const int frame = sweep_frame(step++);
    for (int c = 0; c < r->camera_count(); ++c)
      benchmark::DoNotOptimize(r->intersect_bare(c, frame, 2));
  }
  state.counters["images/s"] = benchmark::Counter(double(state.iterations()) * r->camera_count(),
                                                  benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BareIntersect1MovingScene)
    ->Iterations(kMovingFrames - 1)
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
