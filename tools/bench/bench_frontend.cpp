// Tag front end speed: ms per 640x480 frame for libapriltag detection + OpenCV corner
// refinement (+ undistortion into normalized coordinates) with nthreads = 2, at quad_decimate
// 1 and 2. The frame: a 0.2 m tag36h11 at ~2 m, slightly tilted, on a mid-gray background with
// some clutter and Gaussian noise (sigma 2), drawn by warping the tag bitmap with the
// homography of its projected corners (exact geometry is tested elsewhere; this is for timing).
// BM_FrontEndSequence: rendered sequences tracked frame by frame, before / after the
// full-resolution and shadow searches (docs/frontend.md, "Small tags: recall against tag size").
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"

namespace {
using namespace netvmo::io;
using namespace netvmo::frontend;

Calibration bench_calibration() {
  Calibration c;
  c.width = 640;
  c.height = 480;
  c.K = cv::Matx33d(610.0, 0, 321.7, 0, 605.0, 238.4, 0, 0, 1);
  c.dist = {-0.12, 0.05, 4e-4, -3e-4, 0.0};
  return c;
}

cv::Mat bench_frame(const Calibration& calib) {
  apriltag_family_t* fam = tag36h11_create();
  image_u8_t* im = apriltag_to_image(fam, 0);
  const int total = fam->total_width, border = (total - fam->width_at_border) / 2;
  // bitmap + 1 extra white cell, 16 px per cell
  const int cells = total + 2, px = 16;
  cv::Mat tag(cells * px, cells * px, CV_8UC1, cv::Scalar(230));
  for (int r = 0; r < total; ++r)
    for (int c = 0; c < total; ++c)
      tag(cv::Rect((c + 1) * px, (r + 1) * px, px, px))
          .setTo(im->buf[r * im->stride + c] > 127 ? 230 : 20);
  std::free(im->buf);
  std::free(im);
  const int wb = fam->width_at_border;
  tag36h11_destroy(fam);
  // object corners (tag frame, y up) and their bitmap pixels (row 0 = top = +y)
  const double s = 0.2, h = s / 2;
  std::vector<cv::Point3d> obj = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  const double a = (border + 1) * px, b = (border + 1 + wb) * px;
  std::vector<cv::Point2f> src = {
      {float(a), float(b)}, {float(b), float(b)}, {float(b), float(a)}, {float(a), float(a)}};
  std::vector<cv::Point2d> img;
  // facing the camera (rotation pi about x) with a small tilt, 2 m away
  cv::Matx33d R1, R2;
  cv::Rodrigues(cv::Vec3d(CV_PI, 0, 0), R1);
  cv::Rodrigues(cv::Vec3d(0.2, -0.3, 0.4), R2);
  cv::Vec3d rvec;
  cv::Rodrigues(R1 * R2, rvec);
  cv::projectPoints(obj, rvec, cv::Vec3d(0.15, -0.1, 2.0), cv::Mat(calib.K), cv::noArray(), img);
  std::vector<cv::Point2f> dst(img.begin(), img.end());
  cv::Mat frame(calib.height, calib.width, CV_8UC1, cv::Scalar(128));
  // clutter: a few dark and bright rectangles
  cv::RNG rng(42);
  for (int i = 0; i < 12; ++i)
    cv::rectangle(frame,
                  cv::Rect(rng.uniform(0, 600), rng.uniform(0, 440), rng.uniform(10, 80),
                           rng.uniform(10, 80)),
                  cv::Scalar(rng.uniform(0, 255)), cv::FILLED);
  // the quiet-zone square maps through the same homography
  const cv::Mat H = cv::getPerspectiveTransform(src, dst);
  cv::Mat warped, mask;
  cv::warpPerspective(tag, warped, H, frame.size(), cv::INTER_AREA);
  cv::warpPerspective(cv::Mat(tag.size(), CV_8UC1, cv::Scalar(255)), mask, H, frame.size(),
                      cv::INTER_NEAREST);
  warped.copyTo(frame, mask);
  cv::Mat noise(frame.size(), CV_16SC1);
  rng.fill(noise, cv::RNG::NORMAL, 0, 2);
  cv::Mat f16;
  frame.convertTo(f16, CV_16SC1);
  f16 += noise;
  f16.convertTo(frame, CV_8UC1);
  return frame;
}

void BM_FrontEnd(benchmark::State& state) {
  const Calibration calib = bench_calibration();
  const cv::Mat frame = bench_frame(calib);
  DetectorSettings s;
  s.quad_decimate = static_cast<double>(state.range(0));
  s.nthreads = 2;
  s.refinement = static_cast<Refinement>(state.range(1));
  s.min_white_black_diff = static_cast<int>(state.range(2));
  FrontEnd fe(s);
  int detected = 0, n = 0;
  for (auto _ : state) {
    const Observation o = fe.observe(frame, calib);
    benchmark::DoNotOptimize(o.f_normalized.data());
    detected += o.delta;
    ++n;
  }
  if (detected != n) state.SkipWithError("target not detected in the benchmark frame");
  state.SetLabel(std::string("decimate ") + std::to_string(state.range(0)) + ", refine " +
                 to_string(s.refinement) + ", min_white_black_diff " +
                 std::to_string(state.range(2)));
}

// libapriltag alone (no refinement, no undistortion), nthreads from the argument.
void BM_AprilTagOnly(benchmark::State& state) {
  const Calibration calib = bench_calibration();
  const cv::Mat frame = bench_frame(calib);
  DetectorSettings s;
  s.quad_decimate = static_cast<double>(state.range(0));
  s.nthreads = static_cast<int>(state.range(1));
  s.refinement = Refinement::none;
  TagDetector det(s);
  for (auto _ : state) benchmark::DoNotOptimize(det.detect(frame).all.size());
  state.SetLabel(std::string("decimate ") + std::to_string(state.range(0)) + ", nthreads " +
                 std::to_string(state.range(1)));
}

// The OpenCV refinement step alone on the detected corners.
void BM_RefineOnly(benchmark::State& state) {
  const Calibration calib = bench_calibration();
  const cv::Mat frame = bench_frame(calib);
  DetectorSettings s;
  s.refinement = Refinement::none;
  TagDetector det(s);
  const auto d = det.detect(frame);
  if (!d.target()) {
    state.SkipWithError("target not detected");
    return;
  }
  const auto mode = static_cast<Refinement>(state.range(0));
  for (auto _ : state) {
    auto c = d.target()->corners;
    refine_corners(frame, c, mode, det.border_cells(), &calib);
    benchmark::DoNotOptimize(c.data());
  }
  state.SetLabel(std::string("refine ") + to_string(mode));
}

// The border / quiet-zone check alone on the refined corners (what it adds per frame when the
// target is accepted). arg: the straight-sides test (border_max_bow) off (0) or on (1).
void BM_BorderCheckOnly(benchmark::State& state) {
  const Calibration calib = bench_calibration();
  const cv::Mat frame = bench_frame(calib);
  DetectorSettings s;
  s.border_check = false;
  TagDetector det(s);
  const auto d = det.detect(frame, &calib);
  if (!d.target()) {
    state.SkipWithError("target not detected");
    return;
  }
  const cv::Mat pattern = tag_pattern(s.family, s.target_id);
  DetectorSettings check;
  if (state.range(0) == 0) check.border_max_bow = 0.0;
  // As in the front end: the edge-line fit's corners and samples (refined once more).
  auto corners = d.target()->corners;
  EdgeSamples edges;
  refine_corners(frame, corners, Refinement::edge_lines, det.border_cells(), &calib, &edges);
  bool ok = false;
  for (auto _ : state) {
    const BorderCheck bc =
        check_border(frame, corners, pattern, det.border_cells(), check, &calib, &edges);
    ok = bc.ok && bc.checked;
  }
  if (!ok) state.SkipWithError("the check rejected the benchmark frame");
  state.SetLabel(std::string("border check, calibration with distortion, straight sides ") +
                 (state.range(0) ? "on" : "off"));
}

// The front end on frames rendered from datasets/paper5_render.yaml (its default 2x2 samples and
// sensor noise): camera 1 (tag at ~2 m) and camera 5 (no tag; pillar and textures only), full
// frame or tracking (window around the last detection). args: camera index, tracking.
void BM_FrontEndRendered(benchmark::State& state) {
  const int cam = static_cast<int>(state.range(0));
  const bool tracking = state.range(1) != 0;
  auto scene = netvmo::io::load_render_scenario(std::string(NETVMO_SOURCE_DIR) +
                                                "/datasets/paper5_render.yaml");
  netvmo::render::Renderer r(scene);
  const cv::Mat frame = r.render(cam, 0);
  const auto& k = scene.cameras[static_cast<size_t>(cam)].intrinsics;
  Calibration calib;
  calib.width = k.width;
  calib.height = k.height;
  calib.K = cv::Matx33d(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  for (int j = 0; j < 5; ++j) calib.dist[j] = k.dist[static_cast<size_t>(j)];
  TrackingSettings ts;
  ts.enabled = tracking;
  ts.full_frame_every = 1 << 30;
  FrontEnd fe(DetectorSettings{}, ts);
  TrackState track;
  fe.observe(frame, calib, nullptr, &track);  // primes the window
  bool detected = false;
  for (auto _ : state) detected = fe.observe(frame, calib, nullptr, &track).delta;
  state.SetLabel(std::string("rendered camera ") + std::to_string(cam + 1) +
                 (detected ? " (tag)" : " (no tag)") +
                 (tracking ? ", tracking window" : ", full frame"));
}

// The front end over rendered sequences, each camera tracked frame by frame as in `netvmo run`
// (fresh tracking state per pass): ms per camera-frame and the fraction detected, for the
// search modes of TrackingSettings. args: sequence (0 small_tags.yaml: every 3rd frame of its 3
// cameras, the tag shrinking from 53 to 11 px; 1 moving_target.yaml frames 76-92 of cameras
// 3 and 5, a shadow edge crossing the tag; 2 paper5_render.yaml camera 4, which never sees the
// tag: the cost of the acquisition pass), mode (0 before: decimate 2 everywhere, no
// full-resolution passes, no normalised retry; 1 the defaults; 2 decimate 1 on every frame).
struct Sequence {
  std::vector<Calibration> calib;            // per camera
  std::vector<std::vector<cv::Mat>> images;  // per camera, frames in order
  int target_id = 0;
};

const Sequence& sequence(int which) {
  static std::map<int, Sequence> cache;
  auto it = cache.find(which);
  if (it != cache.end()) return it->second;
  const char* files[] = {"small_tags.yaml", "moving_target.yaml", "paper5_render.yaml"};
  auto scene = netvmo::io::load_render_scenario(std::string(NETVMO_SOURCE_DIR) + "/datasets/" +
                                                files[which]);
  netvmo::render::Renderer r(scene);
  Sequence seq;
  seq.target_id = scene.target().tag.id;
  std::vector<int> cams, frames;
  if (which == 0) {
    cams = {0, 1, 2};
    for (int k = 0; k < r.frame_count(); k += 3) frames.push_back(k);
  } else if (which == 1) {
    cams = {2, 4};
    for (int k = 76; k <= 92; ++k) frames.push_back(k);
  } else {
    cams = {3};
    for (int k = 0; k < 30; ++k) frames.push_back(k);
  }
  for (int c : cams) {
    seq.calib.push_back(netvmo::io::scene_calibration(scene.cameras[static_cast<size_t>(c)]));
    seq.images.emplace_back();
    for (int k : frames) seq.images.back().push_back(r.render(c, k));
  }
  return cache.emplace(which, std::move(seq)).first->second;
}

void BM_FrontEndSequence(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0)), mode = static_cast<int>(state.range(1));
  const Sequence& seq = sequence(which);
  DetectorSettings ds;
  ds.target_id = seq.target_id;
  TrackingSettings ts;
  if (mode == 0) {
    ts.acquire_every = 0;
    ts.full_res_below_px = 0.0;
    ts.shadow_retry = false;
  } else if (mode == 2) {
    ds.quad_decimate = 1.0;
    ts.enabled = false;
  }
  FrontEnd fe(ds, ts);
  int frames = 0, detected = 0;
  double seconds = 0.0;  // wall time in observe(), over every pass
  long passes = 0;
  for (auto _ : state) {
    frames = detected = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t c = 0; c < seq.images.size(); ++c) {
      TrackState track;
      for (const cv::Mat& img : seq.images[c]) {
        detected += fe.observe(img, seq.calib[c], nullptr, &track).delta;
        ++frames;
      }
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++passes;
  }
  state.counters["ms_per_frame"] = 1e3 * seconds / static_cast<double>(passes * frames);
  state.counters["detected"] = static_cast<double>(detected) / std::max(1, frames);
  const char* names[] = {"small_tags", "moving_target shadow frames", "paper5 camera 4 (no tag)"};
  const char* modes[] = {"before (decimate 2 only)", "defaults", "decimate 1 every frame"};
  state.SetLabel(std::string(names[which]) + ", " + modes[mode]);
}

}  // namespace

BENCHMARK(BM_FrontEndSequence)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);
BENCHMARK(BM_FrontEndRendered)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({4, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);
BENCHMARK(BM_AprilTagOnly)
    ->Args({2, 1})
    ->Args({2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RefineOnly)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BorderCheckOnly)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// args: quad_decimate, refinement (0 none, 1 subpix, 2 edges), min_white_black_diff
BENCHMARK(BM_FrontEnd)
    ->Args({1, 0, 20})
    ->Args({1, 2, 20})
    ->Args({2, 0, 20})
    ->Args({2, 1, 20})
    ->Args({2, 2, 20})
    ->Args({1, 2, 5})
    ->Args({2, 2, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

BENCHMARK_MAIN();
