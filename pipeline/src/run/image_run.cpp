#include "netvmo/pipeline/run/image_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/progress.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::run {

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
  // Gershgorin: lambda_max(k_e Delta + k_s L) <= k_e + 2 k_s d_max (docs/observer.md,
  // "Discretisation and stability").
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

TimeGrid time_grid(double first, double last, double dt, int frames) {
  TimeGrid g;
  g.dt = dt;
  g.t0 = first;
  g.frames = frames > 0 ? frames : static_cast<int>(std::floor((last - first) / dt + 1e-9)) + 1;
  return g;
}

TimeGrid time_grid(const sources::NetworkSource& source, int frames) {
  const io::NetworkConfig& net = source.network();
  double first = std::numeric_limits<double>::infinity();
  double last = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    const auto images = sources::camera_images(source, i);
    if (images.empty()) continue;
    first = std::min(first, images.front().second);
    last = std::max(last, images.back().second);
  }
  if (!std::isfinite(first)) first = last = 0.0;
  return time_grid(first, last, 1.0 / net.fps, frames);
}

int latest_at_or_before(const std::vector<double>& times, double t) {
  return static_cast<int>(std::upper_bound(times.begin(), times.end(), t + 1e-9) - times.begin()) -
         1;
}

namespace {

// What the synchronised run and the run on the union of timestamps share: one runner per target,
// one front end per worker thread (every target decided in one pass) and each camera's tracking
// state. Front-end results are stored [target][slot].
struct Pipeline {
  Pipeline(sources::NetworkSource& source, const ImageRunSettings& options, const obs::Graph& graph)
      : source(source),
        options(options),
        n(source.network().cameras.size()),
        targets(source.network().targets),
        workers(std::max(1, std::min<int>(options.workers, static_cast<int>(n)))),
        tracks(n) {
    for (const auto& target : targets) {
      RunnerSettings rs = options.runner;
      rs.tag_size = target.size;
      runners.push_back(std::make_unique<Runner>(graph, believed_at_start(source), rs));
      runners.back()->set_transport(make_transport(options.transport, graph));
    }
    frontend::DetectorSettings ds = options.detector;
    frontend::set_targets(ds, targets);
    // Cameras run in parallel; each worker owns a detector whose libapriltag threads share the
    // remaining cores.
    ds.nthreads = std::max(1, ds.nthreads / workers);
    // The workers' detectors share one libapriltag decoding table (frontend::TagDecoder): built
    // once, not once per worker.
    front_ends.reserve(static_cast<size_t>(workers));
    front_ends.emplace_back(ds, options.tracking);
    const auto decoder = front_ends.front().detector().decoder();
    for (int w = 1; w < workers; ++w) front_ends.emplace_back(ds, options.tracking, decoder);
  }
  static std::vector<obs::SE3> believed_at_start(const sources::NetworkSource& p) {
    std::vector<obs::SE3> g;
    for (size_t i = 0; i < p.network().cameras.size(); ++i) g.push_back(p.camera_believed(i, 0));
    return g;
  }
  // [target][slot] storage for `slots` front-end results.
  std::vector<std::vector<frontend::Observation>> frames_for(size_t slots) const {
    return std::vector<std::vector<frontend::Observation>>(
        targets.size(), std::vector<frontend::Observation>(slots));
  }
  // Camera i's image `frame` through worker w's front end (observe_camera) into cams[j][slot].
  std::exception_ptr observe(int w, size_t i, int frame, cv::Mat& image,
                             std::vector<std::vector<frontend::Observation>>& cams, size_t slot) {
    std::vector<frontend::Observation> out;
    auto error =
        observe_camera(source, i, frame, front_ends[static_cast<size_t>(w)], tracks[i], targets,
                       options.keep_going, image, out, &seconds_reading[static_cast<size_t>(w)]);
    for (size_t j = 0; j < targets.size(); ++j) cams[j][slot] = std::move(out[j]);
    return error;
  }
  // Rethrows an unreadable image's error, or with keep_going turns it into a warning.
  void report(const std::exception_ptr& error, size_t i, int frame, ImageRunResult& result) const {
    if (!error) return;
    if (!options.keep_going) std::rethrow_exception(error);
    try {
      std::rethrow_exception(error);
    } catch (const InputError& e) {
      result.warnings.push_back(std::string(e.what()) + " (camera " +
                                std::to_string(source.network().cameras[i].id) +
                                " blind at frame " + std::to_string(frame) + ")");
    }
  }
  // After frame k's records: the hook, the front-end results kept for the outputs, progress.
  void frame_done(int k, const std::vector<cv::Mat>& images,
                  const std::vector<std::vector<frontend::Observation>>& cams,
                  const std::vector<const FrameRecord*>& records, const FrameHook& hook,
                  ImageRunResult& result, Progress& progress) const {
    if (hook) hook(k, images, cams, records);
    if (options.runner.keep_history)
      for (size_t j = 0; j < targets.size(); ++j) result.target(j).frames.push_back(cams[j]);
    progress.update(k + 1);
  }
  // Every camera whose first image looks resampled by nearest neighbour: a warning each, in
  // camera order.
  void add_resampling_warnings(ImageRunResult& result) const {
    for (size_t i = 0; i < n; ++i)
      if (const auto& r = tracks[i].resampling)
        if (auto w = frontend::resampling_warning(source.network().cameras[i].id, *r))
          result.warnings.push_back(*w);
  }
  // The front end's time by stage, summed over the workers, into the result.
  void add_stage_seconds(ImageRunResult& result) const {
    for (int w = 0; w < workers; ++w) {
      result.seconds_reading += seconds_reading[static_cast<size_t>(w)];
      result.seconds_stages += front_ends[static_cast<size_t>(w)].detector().seconds();
    }
  }
  // Runs f(w) for every worker w, worker 0 on the calling thread; once all have returned,
  // rethrows the error of the lowest worker that threw.
  template <class F>
  void in_parallel(F&& f) const {
    std::vector<std::exception_ptr> failed(static_cast<size_t>(workers));
    const auto run = [&](int w) {
      try {
        f(w);
      } catch (...) {
        failed[static_cast<size_t>(w)] = std::current_exception();
      }
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(run, w);
    run(0);
    for (auto& t : pool) t.join();
    for (const auto& e : failed)
      if (e) std::rethrow_exception(e);
  }

  sources::NetworkSource& source;
  const ImageRunSettings& options;
  size_t n;
  const std::vector<io::TargetConfig>& targets;
  std::vector<std::unique_ptr<Runner>> runners;  // one per target
  int workers;
  std::vector<frontend::FrontEnd> front_ends;
  std::vector<frontend::TrackState> tracks;  // one worker at a time per camera
  std::vector<double> seconds_reading = std::vector<double>(static_cast<size_t>(workers), 0.0);
};

// The front end of a synchronised run, running ahead of the observer on its own threads (one
// per Pipeline worker, each with its own detector). Camera i's frame k is detected once its frame
// k - 1 is (its tracking state) and while k < the observer's frame + kLookAhead; a free worker
// takes the earliest such frame, among equals the camera that took longest the last time (so the
// slow cameras, typically the blind ones searching whole images, start first). A slow camera's
// frame thus no longer idles the other workers: they move on to the next frames of the others.
// Results are those of detecting each camera's frames in order, whichever worker does it.
class FrontEndAhead {
 public:
  static constexpr int kLookAhead = 3;  ///< frames in flight (images and results held)

  FrontEndAhead(Pipeline& p, int frames)
      : p_(p),
        frames_(frames),
        ahead_(p.source.one_frame_at_a_time() ? 1 : kLookAhead),
        next_(p.n, 0),
        busy_(p.n, false),
        cost_(p.n, 0.0),
        done_(static_cast<size_t>(ahead_), 0) {
    for (int s = 0; s < ahead_; ++s) {
      images_.emplace_back(p.n);
      cams_.push_back(p.frames_for(p.n));
      errors_.emplace_back(p.n);
    }
    try {
      for (int w = 0; w < p.workers; ++w) threads_.emplace_back([this, w] { work(w); });
    } catch (...) {  // a thread that cannot start: stop the others before unwinding
      stop();
      throw;
    }
  }
  ~FrontEndAhead() { stop(); }
  FrontEndAhead(const FrontEndAhead&) = delete;
  FrontEndAhead& operator=(const FrontEndAhead&) = delete;

  /// Waits until every camera's frame k is detected; its results stay until release(k). A
  /// front end's unexpected error is rethrown by the first wait for a frame it left unfinished.
  void wait(int k) {
    std::unique_lock<std::mutex> lock(mu_);
    changed_.wait(lock, [&] { return failure_ || done_[slot(k)] == p_.n; });
    if (done_[slot(k)] != p_.n) std::rethrow_exception(failure_);
  }
  std::vector<cv::Mat>& images(int k) { return images_[slot(k)]; }
  std::vector<std::vector<frontend::Observation>>& cams(int k) { return cams_[slot(k)]; }
  std::vector<std::exception_ptr>& errors(int k) { return errors_[slot(k)]; }
  /// Frame k is used: its slot takes frame k + ahead_.
  void release(int k) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      done_[slot(k)] = 0;
      consumed_ = k + 1;
    }
    changed_.notify_all();
  }

 private:
  size_t slot(int k) const { return static_cast<size_t>(k % ahead_); }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    changed_.notify_all();
    for (auto& t : threads_) t.join();
    threads_.clear();
  }
  // The camera whose next frame comes first, or n when none may start now.
  size_t pick() const {
    size_t best = p_.n;
    for (size_t i = 0; i < p_.n; ++i) {
      if (busy_[i] || next_[i] >= frames_ || next_[i] >= consumed_ + ahead_) continue;
      if (best == p_.n || next_[i] < next_[best] ||
          (next_[i] == next_[best] && cost_[i] > cost_[best]))
        best = i;
    }
    return best;
  }
  void work(int w) {
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
      size_t i = p_.n;
      changed_.wait(lock, [&] {
        if (stop_ || failure_) return true;
        i = pick();
        return i < p_.n ||
               std::all_of(next_.begin(), next_.end(), [&](int f) { return f >= frames_; });
      });
      if (stop_ || failure_ || i == p_.n) return;
      const int k = next_[i];
      busy_[i] = true;
      lock.unlock();
      const auto t0 = Clock::now();
      std::exception_ptr failure;
      try {
        errors_[slot(k)][i] = p_.observe(w, i, k, images_[slot(k)][i], cams_[slot(k)], i);
      } catch (...) {
        failure = std::current_exception();
      }
      const double cost = seconds_since(t0);
      lock.lock();
      busy_[i] = false;
      if (failure && !failure_) failure_ = failure;
      next_[i] = k + 1;
      cost_[i] = cost;
      ++done_[slot(k)];
      changed_.notify_all();
    }
  }

  Pipeline& p_;
  const int frames_;
  const int ahead_;  ///< frames in flight: kLookAhead, or 1 (NetworkSource::one_frame_at_a_time)
  std::mutex mu_;
  std::condition_variable changed_;
  std::vector<int> next_;     ///< per camera: its next frame to detect
  std::vector<bool> busy_;    ///< per camera: a worker is detecting its frame
  std::vector<double> cost_;  ///< per camera: seconds its last frame took
  std::vector<size_t> done_;  ///< per slot: cameras done with its frame
  int consumed_ = 0;          ///< frames the observer is done with
  bool stop_ = false;
  std::exception_ptr failure_;  ///< a front end's unexpected error: the run stops
  std::vector<std::vector<cv::Mat>> images_;
  std::vector<std::vector<std::vector<frontend::Observation>>> cams_;
  std::vector<std::vector<std::exception_ptr>> errors_;
  std::vector<std::thread> threads_;
};

// One camera image of a run on the union of timestamps.
struct Event {
  double t = 0.0;
  size_t camera = 0;
  int frame = 0;
};

// Cameras on their own clocks: the observer advances on the union of their image times (see
// run_images in the header). Up to each grid time it takes every camera's images in time order;
// an image changes only its camera's delta_i and measurement, held until its next image. Every
// grid time is recorded with what the cameras hold then.
class UnionRun {
 public:
  UnionRun(Pipeline& p, ImageRunResult& result)
      : p_(p),
        result_(result),
        moving_(p.source.cameras_move()),
        grid_(time_grid(p.source)),
        held_(p.targets.size()) {
    if (p.options.max_frames) grid_.frames = std::min(grid_.frames, *p.options.max_frames);
    events_ = events_until(p.source, grid_.time(grid_.frames - 1));
    net_start_ = network_start(events_, p.n);
    for (auto& h : held_) h.resize(p.n);
    held_cams_ = p.frames_for(p.n);
    held_images_.resize(p.n);
    held_frame_.assign(p.n, -1);
    now_ = events_.empty() ? grid_.t0 : std::min(grid_.t0, events_.front().t);
    result.union_of_timestamps = true;
    result.time_origin_s = 0.0;  // the images' own times
    result.source_frames.assign(static_cast<size_t>(grid_.frames), std::vector<int>(p.n, -1));
  }

  void run(const FrameHook& hook) {
    const auto t_start = Clock::now();
    Progress progress("run", grid_.frames, p_.options.progress);
    for (int k = 0; k < grid_.frames; ++k) {
      const double tk = grid_.time(k);
      for (; next_ < events_.size() && events_[next_].t <= tk + 1e-9; ++next_) {
        if (next_ == detected_end_) detect_from(next_);
        take(next_, tk);
      }
      record(k, hook, progress);
    }
    progress.finish();
    result_.seconds = seconds_since(t_start);
    p_.add_stage_seconds(result_);
  }

 private:
  // Every camera's images up to t_end, in time order (among equal times, by camera).
  static std::vector<Event> events_until(sources::NetworkSource& source, double t_end) {
    std::vector<Event> events;
    for (size_t i = 0; i < source.network().cameras.size(); ++i)
      for (const auto& [k, t] : sources::camera_images(source, i))
        if (t <= t_end + 1e-9) events.push_back({t, i, k});
    std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
      return a.t < b.t || (a.t == b.t && a.camera < b.camera);
    });
    return events;
  }
  // The network starts once every camera has taken its first image (the latest first image of a
  // camera that has any): earlier images only set their cameras' held measurements, so every
  // camera that sees the target starts from its own PnP pose, as in a synchronised run, instead
  // of from a neighbour that happened to start first.
  static double network_start(const std::vector<Event>& events, size_t n) {
    double start = -std::numeric_limits<double>::infinity();
    std::vector<bool> has_image(n, false);
    for (const auto& e : events)
      if (!has_image[e.camera]) {
        has_image[e.camera] = true;
        start = std::max(start, e.t);
      }
    return start;
  }
  // The front end runs ahead in batches of events [detected_base_, detected_end_): each worker
  // takes its cameras' images in time order.
  void detect_from(size_t first) {
    const size_t batch = std::max<size_t>(2 * p_.n, 8);
    detected_base_ = first;
    detected_end_ = std::min(events_.size(), first + batch);
    const size_t size = detected_end_ - detected_base_;
    images_.assign(size, cv::Mat());
    cams_ = p_.frames_for(size);
    errors_.assign(size, nullptr);
    const auto t_fe = Clock::now();
    p_.in_parallel([&](int w) {
      for (size_t e = detected_base_; e < detected_end_; ++e)
        if (static_cast<int>(events_[e].camera % static_cast<size_t>(p_.workers)) == w)
          errors_[e - detected_base_] =
              p_.observe(w, events_[e].camera, events_[e].frame, images_[e - detected_base_], cams_,
                         e - detected_base_);
    });
    result_.seconds_front_end += seconds_since(t_fe);
  }
  // Event e, before grid time tk: the network advanced to its time, then its camera's held
  // measurement replaced (the truth at the image's time is for the exact error model).
  void take(size_t e, double tk) {
    const Event& ev = events_[e];
    const size_t b = e - detected_base_, i = ev.camera;
    p_.report(errors_[b], i, ev.frame, result_);
    const auto t_obs = Clock::now();
    advance_to(ev.t);
    if (moving_) set_camera_motion(now_, tk);
    for (size_t j = 0; j < p_.targets.size(); ++j) {
      held_cams_[j][i] = cams_[j][b];
      held_[j][i] = measurement_of(held_cams_[j][i], p_.source.target_truth_at(ev.t, j),
                                   p_.source.camera_truth_at(i, ev.t));
      // estimates.csv: the camera's estimate at its image's time.
      const auto est = p_.runners[j]->estimate_world(i);
      result_.target(j).own_estimates.push_back({ev.frame, ev.t, i, held_[j][i].delta,
                                                 est.has_value(),
                                                 est.value_or(obs::SE3::Identity())});
    }
    held_images_[i] = images_[b];
    held_frame_[i] = ev.frame;
    result_.seconds_observer += seconds_since(t_obs);
  }
  // Grid time k: the network advanced to it and every target's frame recorded with what the
  // cameras hold.
  void record(int k, const FrameHook& hook, Progress& progress) {
    const auto t_obs = Clock::now();
    const double tk = grid_.time(k);
    advance_to(tk);
    if (moving_) set_camera_motion(now_, k + 1 < grid_.frames ? grid_.time(k + 1) : now_);
    std::vector<std::optional<obs::SE3>> true_wi(p_.n);
    for (size_t i = 0; i < p_.n; ++i) true_wi[i] = p_.source.camera_truth_at(i, tk);
    std::vector<const FrameRecord*> records(p_.targets.size());
    for (size_t j = 0; j < p_.targets.size(); ++j) {
      const auto target = p_.source.target_truth_at(tk, j);
      records[j] =
          &p_.runners[j]->record(k, tk, measurements_of(held_cams_[j], target, true_wi), target);
    }
    result_.source_frames[static_cast<size_t>(k)] = held_frame_;
    result_.seconds_observer += seconds_since(t_obs);
    p_.frame_done(k, held_images_, held_cams_, records, hook, result_, progress);
  }
  // The network from now_ to `to` (not before it starts) in pieces of at most one grid step,
  // each with the sub-step rule; now_ moves to `to` if that is later.
  void advance_to(double to) {
    const double span = to - std::max(now_, net_start_);
    if (span > 0) {
      const int pieces = std::max(1, static_cast<int>(std::ceil(span / grid_.dt - 1e-9)));
      for (size_t j = 0; j < p_.targets.size(); ++j)
        for (int q = 0; q < pieces; ++q) p_.runners[j]->advance(span / pieces, held_[j]);
    }
    now_ = std::max(now_, to);
  }
  // Every camera's believed pose at t and, unless ignored, its velocity towards t_next.
  void set_camera_motion(double t, double t_next) {
    std::vector<obs::SE3> g(p_.n);
    std::vector<obs::Vec6> V(p_.n, obs::Vec6::Zero());
    for (size_t i = 0; i < p_.n; ++i) {
      g[i] = p_.source.camera_believed_at(i, t);
      if (!p_.options.ignore_camera_velocity && t_next > t)
        V[i] = camera_velocity(g[i], p_.source.camera_believed_at(i, t_next), t_next - t);
    }
    for (auto& r : p_.runners) r->set_camera_motion(g, V);
  }

  Pipeline& p_;
  ImageRunResult& result_;
  const bool moving_;  ///< the cameras move: their poses and velocities are set at every step
  TimeGrid grid_;
  std::vector<Event> events_;
  double net_start_ = 0.0;
  double now_ = 0.0;  ///< the time the network has advanced to
  size_t next_ = 0;   ///< the next event to take
  // What camera i holds since its latest image: held_[j][i] its measurement of target j,
  // held_cams_[j][i] its front end's result, held_images_[i] the image, held_frame_[i] its frame
  // (-1 before the first).
  std::vector<std::vector<obs::Measurement>> held_;
  std::vector<std::vector<frontend::Observation>> held_cams_;
  std::vector<cv::Mat> held_images_;
  std::vector<int> held_frame_;
  // The batch of events the front end has detected: [detected_base_, detected_end_).
  size_t detected_base_ = 0, detected_end_ = 0;
  std::vector<cv::Mat> images_;
  std::vector<std::vector<frontend::Observation>> cams_;
  std::vector<std::exception_ptr> errors_;
};

}  // namespace

ImageRunResult run_images(sources::NetworkSource& source, const ImageRunSettings& options,
                          const FrameHook& hook) {
  const io::NetworkConfig& net = source.network();
  const size_t n = net.cameras.size();
  const obs::Graph graph = network_graph(net);
  // The synchronised run steps every camera together by 1 / fps; cameras on their own clocks,
  // or a common clock at another rate, run on the union of their image times.
  const bool own_clocks =
      sources::clock_mismatch(source).has_value() || sources::irregular_clock(source);
  checked_rounds(1.0 / net.fps, options.runner.k_e, options.runner.k_s, graph.max_degree(),
                 options.runner.rounds);

  Pipeline p(source, options, graph);
  const size_t T = p.targets.size();
  const bool moving = source.cameras_move();
  std::vector<obs::SE3> g_wi = Pipeline::believed_at_start(source);
  std::vector<std::optional<obs::SE3>> true_wi(n);
  std::vector<obs::Vec6> V_wi(n, obs::Vec6::Zero());

  ImageRunResult result;
  result.other_targets.resize(T - 1);
  result.warnings = source.warnings();
  const double dt = 1.0 / net.fps;
  result.substeps = p.runners[0]->substeps(dt);
  result.step_factor = p.runners[0]->step_factor(dt);
  if (auto w = step_factor_warning(result.substeps, result.step_factor))
    result.warnings.push_back(*w);
  const auto histories = [&] {
    for (size_t j = 0; j < T; ++j) result.target(j).history = p.runners[j]->history();
  };
  if (own_clocks) {
    UnionRun(p, result).run(hook);
    histories();
    p.add_resampling_warnings(result);
    return result;
  }
  int frames = source.frame_count();
  if (options.max_frames) frames = std::min(frames, *options.max_frames);

  Progress progress("run", frames, options.progress);
  const auto t_start = Clock::now();
  std::vector<const FrameRecord*> records(T);
  {
    FrontEndAhead ahead(p, frames);
    for (int k = 0; k < frames; ++k) {
      const auto t_fe = Clock::now();
      ahead.wait(k);
      const auto& images = ahead.images(k);
      const auto& cams = ahead.cams(k);
      for (size_t i = 0; i < n; ++i) p.report(ahead.errors(k)[i], i, k, result);
      result.seconds_front_end += seconds_since(t_fe);

      const auto t_obs = Clock::now();
      for (size_t i = 0; i < n; ++i) true_wi[i] = source.camera_truth(i, k);
      if (moving) {
        for (size_t i = 0; i < n; ++i) {
          g_wi[i] = source.camera_believed(i, k);
          if (!options.ignore_camera_velocity)
            V_wi[i] = camera_velocity(g_wi[i], source.camera_believed(i, k + 1), dt);
        }
        for (auto& r : p.runners) r->set_camera_motion(g_wi, V_wi);
      }
      for (size_t j = 0; j < T; ++j) {
        const auto target = source.target_truth(k, j);
        records[j] = &p.runners[j]->process(k, k * dt, dt,
                                            measurements_of(cams[j], target, true_wi), target);
      }
      result.seconds_observer += seconds_since(t_obs);
      p.frame_done(k, images, cams, records, hook, result, progress);
      ahead.release(k);
    }
  }  // the front end's threads end here
  progress.finish();
  result.seconds = seconds_since(t_start);
  p.add_stage_seconds(result);
  histories();
  p.add_resampling_warnings(result);
  return result;
}

}  // namespace netvmo::run
