#include "netvmo/pipeline/run/image_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <thread>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/progress.hpp"

namespace netvmo::run {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
}  // namespace

obs::Graph network_graph(const io::NetworkConfig& net) {
  std::vector<obs::Graph::Edge> edges;
  for (const auto& [a, b] : net.edges) edges.emplace_back(net.index_of(a), net.index_of(b));
  obs::Graph g(static_cast<int>(net.cameras.size()), edges);
  if (!g.connected()) {
    std::vector<int> labels;
    for (const auto& c : net.cameras) labels.push_back(c.id);
    throw InputError(net.source + ": edges: the communication graph is disconnected " +
                     "(Assumption 1); components " +
                     obs::describe_components(g.components(), labels) +
                     ": add an edge joining them");
  }
  return g;
}

std::vector<CameraInput> camera_inputs(const std::vector<CameraFrame>& cams,
                                       const std::optional<obs::SE3>& target,
                                       const std::vector<std::optional<obs::SE3>>& true_wi) {
  std::vector<CameraInput> in(cams.size());
  for (size_t i = 0; i < cams.size(); ++i) {
    in[i].delta = cams[i].obs.delta;
    in[i].f = cams[i].obs.f_normalized;  // (eq:visual_mea) with lambda = 1
    in[i].points_o = cams[i].points_o;   // a bundle's seen corners (empty: the tag's square)
    in[i].g_io_pnp = cams[i].g_io_pnp;
    if (target && true_wi[i])
      in[i].g_io_true = true_wi[i]->inverse() * *target;  // g_io = g_wi^-1 g_wo
  }
  return in;
}

obs::Vec6 camera_velocity(const obs::SE3& g_k, const obs::SE3& g_k1, double dt) {
  if (g_k.isApprox(g_k1, 0.0)) return obs::Vec6::Zero();
  return obs::log_se3(g_k.inverse() * g_k1) / dt;
}

std::optional<std::string> step_factor_warning(int substeps, double step_factor) {
  if (step_factor < 2.0) return std::nullopt;
  char b[200];
  std::snprintf(b, sizeof b,
                "%d exchange rounds per frame give h * (the estimator's rate bound; vmo: "
                "k_e + 2 k_s d_max) = %.2f >= 2: the discrete observer is unstable; use more "
                "rounds",
                substeps, step_factor);
  return std::string(b);
}

int checked_rounds(double dt, double k_e, double k_s, int max_degree, int rounds) {
  // Gershgorin: lambda_max(k_e Delta + k_s L) <= k_e + 2 k_s d_max (README, "Discretisation").
  const double bound = k_e + 2.0 * k_s * max_degree;
  if (!std::isfinite(bound) || !(k_e > 0) || !(k_s >= 0))
    throw InputError("--ke " + std::to_string(k_e) + ", --ks " + std::to_string(k_s) +
                     ": gains must be finite, k_e > 0 and k_s >= 0");
  const double stable = std::max(1.0, std::ceil(dt * bound - 1e-12));           // h bound <= 1
  const double unstable_below = std::max(1.0, std::floor(dt * bound / 2) + 1);  // h bound < 2
  char range[400];
  std::snprintf(range, sizeof range,
                "with these gains and graph (k_e + 2 k_s d_max = %.6g, d_max = %d, dt = %.6g s) "
                "N >= %.6g rounds keep h (k_e + 2 k_s d_max) <= 1 (stable, no oscillation); "
                "N < %.6g give h (k_e + 2 k_s d_max) >= 2, where it may diverge (it does once "
                "h lambda_max >= 2)",
                bound, max_degree, dt, stable, unstable_below);
  const int limit = kMaxRoundsPerFrame;
  if (rounds > limit)
    throw InputError("--rounds " + std::to_string(rounds) + ": at most " + std::to_string(limit) +
                     " exchange rounds per frame (each is an observer step of every camera: " +
                     std::to_string(limit) + " already cost ~50 ms a frame); " + range +
                     "; 0 picks the smallest stable N");
  if (rounds <= 0 && stable > limit)
    throw InputError("--ke/--ks: the gains need more than " + std::to_string(limit) +
                     " exchange rounds per frame; " + range + "; lower the gains");
  return rounds > 0 ? rounds : static_cast<int>(stable);
}

ImageRunResult run_images(sources::NetworkSource& provider, const ImageRunOptions& options,
                          const FrameHook& hook) {
  const io::NetworkConfig& net = provider.network();
  const size_t n = net.cameras.size();
  const obs::Graph graph = network_graph(net);
  if (auto m = sources::clock_mismatch(provider))
    throw InputError(*m +
                     ": the in-process run needs one clock for every camera (cameras on "
                     "their own clocks run with `netvmo launch --mode async`)");
  checked_rounds(1.0 / net.fps, options.runner.k_e, options.runner.k_s, graph.max_degree(),
                 options.runner.rounds);

  run::RunnerSettings rs = options.runner;
  rs.tag_size = net.target.size;
  const bool moving = provider.cameras_move();
  std::vector<obs::SE3> g_wi;
  for (size_t i = 0; i < n; ++i) g_wi.push_back(provider.camera_believed(i, 0));
  run::NetworkRunner runner(graph, g_wi, rs);
  runner.set_transport(make_transport(options.transport, graph));

  frontend::DetectorSettings ds = options.detector;
  frontend::set_target(ds, net.target);
  const int workers = std::max(1, std::min<int>(options.workers, static_cast<int>(n)));
  // Cameras run in parallel; each worker owns a detector whose libapriltag threads share the
  // remaining cores.
  ds.nthreads = std::max(1, ds.nthreads / workers);
  std::vector<frontend::FrontEnd> front_ends;
  for (int w = 0; w < workers; ++w) front_ends.emplace_back(ds, options.tracking);
  std::vector<frontend::TrackState> tracks(n);  // camera i is always handled by worker i % workers

  std::vector<std::optional<obs::SE3>> true_wi(n);
  std::vector<obs::Vec6> V_wi(n, obs::Vec6::Zero());

  ImageRunResult result;
  result.warnings = provider.warnings();
  const double dt = 1.0 / net.fps;
  result.substeps = runner.substeps(dt);
  result.step_factor = runner.step_factor(dt);
  if (auto w = step_factor_warning(result.substeps, result.step_factor))
    result.warnings.push_back(*w);
  int frames = provider.frame_count();
  if (options.max_frames) frames = std::min(frames, *options.max_frames);

  Progress progress("run", frames, options.progress);
  const auto t_start = Clock::now();
  std::vector<cv::Mat> images(n);
  std::vector<CameraFrame> cams(n);
  std::vector<std::exception_ptr> errors(n);
  for (int k = 0; k < frames; ++k) {
    const auto t_fe = Clock::now();
    auto work = [&](int w) {
      for (size_t i = static_cast<size_t>(w); i < n; i += static_cast<size_t>(workers)) {
        cams[i] = CameraFrame{};
        errors[i] = nullptr;
        try {
          images[i] = provider.read(i, k);
        } catch (const InputError&) {
          images[i].release();
          if (!options.keep_going) {
            errors[i] = std::current_exception();
            continue;
          }
          cams[i].read_failed = true;
          errors[i] = std::current_exception();
          continue;
        }
        cams[i].obs = front_ends[static_cast<size_t>(w)].observe(images[i], provider.calibration(i),
                                                                 nullptr, &tracks[i]);
        if (cams[i].obs.delta) {
          const auto model = frontend::observation_model(net.target, cams[i].obs);
          const auto pose = frontend::pnp_pose(cams[i].obs.f_normalized, model);
          if (pose) cams[i].g_io_pnp = pose->g_io;
          if (!net.target.bundle.empty()) cams[i].points_o = model.points_o;
        }
      }
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(work, w);
    work(0);
    for (auto& t : pool) t.join();
    for (size_t i = 0; i < n; ++i) {
      if (!errors[i]) continue;
      if (!options.keep_going) std::rethrow_exception(errors[i]);
      try {
        std::rethrow_exception(errors[i]);
      } catch (const InputError& e) {
        result.warnings.push_back(std::string(e.what()) + " (camera " +
                                  std::to_string(net.cameras[i].id) + " blind at frame " +
                                  std::to_string(k) + ")");
      }
    }
    result.seconds_front_end += seconds_since(t_fe);

    const auto t_obs = Clock::now();
    for (size_t i = 0; i < n; ++i) true_wi[i] = provider.camera_truth(i, k);
    if (moving) {
      for (size_t i = 0; i < n; ++i) {
        g_wi[i] = provider.camera_believed(i, k);
        if (!options.ignore_camera_velocity)
          V_wi[i] = camera_velocity(g_wi[i], provider.camera_believed(i, k + 1), dt);
      }
      runner.set_camera_motion(g_wi, V_wi);
    }
    const auto target = provider.target_truth(k);
    const auto in = camera_inputs(cams, target, true_wi);
    const auto& record = runner.process(k, k * dt, dt, in, target);
    result.seconds_observer += seconds_since(t_obs);
    if (hook) hook(k, images, cams, record);
    if (options.runner.keep_history) result.frames.push_back(cams);
    progress.update(k + 1);
  }
  progress.finish();
  result.seconds = seconds_since(t_start);
  result.history = runner.history();
  return result;
}

}  // namespace netvmo::run
