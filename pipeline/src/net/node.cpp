#include "netvmo/pipeline/net/node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/exchange.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/net/faulty_transport.hpp"
#include "netvmo/pipeline/net/node_journal.hpp"
#include "netvmo/pipeline/net/ros_publisher.hpp"
#include "netvmo/pipeline/net/socket_drops.hpp"
#include "netvmo/pipeline/run/camera_step.hpp"
#include "netvmo/pipeline/run/ros_frame.hpp"
#include "netvmo/pipeline/sources/topic_network.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using obs::SE3;

namespace {

// A row of node_<id>_links.csv: the neighbours (their camera ids) whose estimate is in the
// mutual term after frame k.
std::string links_row(int k, double t, const obs::CameraObserver& net,
                      const std::vector<int>& labels) {
  std::string in_term;
  for (size_t a = 0; a < net.latest().size(); ++a)
    if (net.latest()[a] && net.latest()[a]->initialized)
      in_term += (in_term.empty() ? "" : " ") +
                 std::to_string(labels[static_cast<size_t>(net.neighbours()[a])]);
  return std::to_string(k) + "," + io::exact_text(t) + "," + in_term + "\n";
}

// A frame on the camera's ROS 2 topics (run::ros_frame): its measurement, its estimate and the
// neighbours' estimates it holds.
void publish_frame(RosPublisher& ros, int camera_id, double t, const frontend::Observation& cam,
                   const obs::CameraObserver& net) {
  std::vector<SE3> neighbours_w;
  for (const auto& m : net.latest())
    if (m && m->initialized) neighbours_w.push_back(m->g_w);
  const std::optional<SE3> estimate =
      net.initialized() ? std::optional<SE3>(net.estimate_world()) : std::nullopt;
  const run::RosFrame f = run::ros_frame(camera_id, t, cam, estimate, neighbours_w);
  if (f.measurement) ros.measurement(*f.measurement);
  if (f.average_pose) ros.average_pose(*f.average_pose);
  if (!f.tf.empty()) ros.tf(f.tf);
}

void sleep_until_epoch(double t) {
  const double wait = t - epoch_seconds();
  if (wait > 0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
}

// The common start from `file` (one number, seconds since the epoch), waiting for it to
// appear for at most timeout_s.
double read_start(const fs::path& file, double timeout_s) {
  const double give_up = epoch_seconds() + timeout_s;
  for (;;) {
    std::ifstream in(file);
    double t = 0;
    if (in >> t) return t;
    if (epoch_seconds() > give_up)
      throw std::runtime_error(file.string() + ": no common start within " +
                               std::to_string(timeout_s) + " s");
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

// A node's CSV output, written as it goes into <file>.partial (flushed after every frame, so a
// node killed mid-run leaves every frame it finished) and renamed to <file> when the node ends.
// With `resume` (a restarted node), a killed predecessor's finished rows of frames before
// `first` are carried over.
class RowJournal {
 public:
  RowJournal(fs::path file, const std::string& header, bool resume, int first)
      : file_(std::move(file)), partial_(partial_path(file_)) {
    std::string kept;
    if (resume) {
      std::ifstream in(partial_);
      std::string line;
      std::getline(in, line);  // header
      while (std::getline(in, line)) {
        if (in.eof()) break;  // the last line had no newline: cut off by the kill
        const auto comma = line.find(',');
        const auto k = io::parse_int(line.substr(0, comma));
        if (comma != std::string::npos && k && *k < first) kept += line + "\n";
      }
    }
    out_.open(partial_, std::ios::trunc);
    if (!out_) throw InputError(partial_.string() + ": cannot write");
    out_ << header << "\n" << kept;
    out_.flush();
  }
  void row(const std::string& line) { out_ << line; }
  void flush() { out_.flush(); }
  void commit() {
    out_.close();
    if (!out_) throw InputError(partial_.string() + ": write failed");
    fs::rename(partial_, file_);
  }

 private:
  fs::path file_, partial_;
  std::ofstream out_;
};

// What a node ran: its setup and discovery times, and each exchange round's publish and receive
// [us] (lock-step: the wait for the neighbours too), a frame's first round (which also waits for
// the neighbours' front ends) apart from the others.
struct NodeTimes {
  double setup_s = 0.0, discovery_s = 0.0;
  bool discovered = false;
  std::vector<double> first_round_us, round_us;
};

// node_<id>.json: the run's options (the same for every node of a run: netvmo merge checks
// them), statistics, the timings, each neighbour's clock as the exchange measured it
// (`clocks_of`), warnings and notes.
nlohmann::json node_json(const NodeSettings& o, const NodeSummary& summary, int frames,
                         int dataset_frames, const LiveCamera* camera, const NodeTimes& times,
                         const ClockSync& clocks_of, const std::vector<int>& neighbours,
                         const std::vector<int>& labels, double clock) {
  nlohmann::json j;
  j["camera"] = o.camera_id;
  j["mode"] = to_string(o.dds.mode);
  j["domain"] = o.dds.domain;
  j["frames"] = frames;
  j["dataset_frames"] = dataset_frames;
  if (camera) {
    j["image_topic"] = camera->image_topic();
    j["images_out_of_order"] = camera->out_of_order();  // dropped: stamp not after the last
  }
  // What the merge of the run's outputs needs (netvmo merge): the same for every node of a run.
  j["options"] = {{"estimator", o.run.runner.estimator},
                  {"k_e", o.run.runner.k_e},
                  {"k_s", o.run.runner.k_s},
                  {"error", o.run.runner.error_model},
                  {"init", run::to_string(o.run.runner.init)},
                  {"rounds", o.run.runner.rounds}};
  j["rounds_per_frame"] = summary.substeps;
  j["seconds"] = summary.seconds;
  const auto quantile = [&](std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    const auto at = v.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), at, v.end());
    return *at;
  };
  j["timing"] = {{"setup_s", times.setup_s},
                 {"discovery_s", times.discovery_s},
                 {"discovered", times.discovered},
                 {"rounds", times.first_round_us.size() + times.round_us.size()},
                 {"round_median_us", quantile(times.round_us, 0.5)},
                 {"round_p99_us", quantile(times.round_us, 0.99)},
                 {"first_round_median_us", quantile(times.first_round_us, 0.5)},
                 {"first_round_p99_us", quantile(times.first_round_us, 0.99)}};
  j["messages"] = {{"sent", summary.stats.sent},
                   {"received", summary.stats.received},
                   {"dropped", summary.stats.dropped},
                   {"late", summary.stats.late},
                   {"foreign", summary.stats.foreign}};
  nlohmann::json rej;
  for (size_t v = 1; v < summary.refused.size(); ++v)
    rej[obs::to_string(static_cast<obs::MessageVerdict>(v))] = summary.refused[v];
  j["messages"]["rejected"] = rej;
  j["messages"]["forgotten_stale"] = summary.forgotten;
  j["messages"]["kernel_drops"] =
      summary.kernel_drops ? nlohmann::json(*summary.kernel_drops) : nlohmann::json(nullptr);
  j["first_frame"] = summary.first_frame;
  j["join_rounds"] = summary.join_rounds;
  // Each neighbour's clock as this node's exchange measured it (ClockSync; netvmo merge aligns
  // the nodes' rows with them).
  nlohmann::json clocks = nlohmann::json::array();
  for (const int nb : neighbours)
    if (const auto c = clocks_of.offset(nb)) {
      nlohmann::json e = {{"camera", labels[static_cast<size_t>(nb)]},
                          {"offset_s", c->offset_s},
                          {"round_trips", c->round_trips}};
      e["delay_s"] = c->round_trip() ? nlohmann::json(c->delay_s) : nlohmann::json(nullptr);
      clocks.push_back(e);
    }
  j["clock"] = {{"neighbours", clocks},
                {"ignored_samples", clocks_of.ignored()},
                {"emulated_offset_s", clock}};
  j["warnings"] = summary.warnings;
  j["notes"] = summary.notes;
  return j;
}

// One camera's process, as run_node runs it, in four steps: set up (Node(): its network, its
// observers and front end as the in-process run's, its frames' clock), connect() to its
// neighbours, start() on the common clock, then run() its frames, each with the run's exchange
// rounds.
class Node {
 public:
  Node(const fs::path& dataset, const NodeSettings& o);
  NodeSummary run(const fs::path& out_dir);

 private:
  using Clock = std::chrono::steady_clock;

  void check_modes() const;
  void count_frames();
  void connect();
  std::optional<double> start();
  const frontend::Observation& observe(int k);
  void exchange_rounds(int k, const obs::Measurement& z, double start, obs::JoinHold& join,
                       obs::Transport& exchange);
  void finish(int k, const FaultyTransport& faulty);

  // Lock-step: every frame lasts the dataset's 1/fps, as in the in-process run. Async: the
  // camera's own images, from one image's time to the next (timestamps.csv, else frame / its
  // fps), the last one lasting its nominal 1/fps.
  double frame_time(int k) const { return async_ ? source_->frame_time(si_, k) : k * dt_; }
  double frame_length(int k);
  // Sub-steps as NetworkedObserver::substeps, by the same stability rule for each frame's
  // length: the independent baseline (k_s = 0) needs fewer.
  int substeps(double len, const obs::CameraObserver& c) const {
    return obs::frame_substeps(len, c.settings(), graph_.max_degree());
  }

  const NodeSettings& o_;
  const Clock::time_point t_start_ = Clock::now();
  const bool live_, async_;
  sources::TopicNetwork* topics_ = nullptr;  // live: the network the images are appended to
  const std::unique_ptr<sources::NetworkSource> source_;
  const io::NetworkConfig& cfg_;
  const int self_;
  const size_t si_;
  const obs::Graph graph_;
  std::vector<int> labels_;
  run::RunnerSettings rs_;
  std::optional<obs::CameraObserver> net_, ind_;  // networked, and the independent baseline
  double dt_ = 0.0, dt_own_ = 0.0;
  int own_frames_ = 0;
  std::vector<io::TargetConfig> targets_;
  std::optional<frontend::FrontEnd> front_end_;
  frontend::TrackState track_;
  std::vector<frontend::Observation> cams_;
  int frames_ = 0;
  int dataset_frames_ = 0;  // the run's, on the dataset's clock (live: none)
  double t0_ = 0.0;
  // What this node's clock says of a time of the run (its stamps: rows, messages, ROS 2): the
  // dataset's time plus its host's clock error (DdsSettings::clock_offset_s; 0 on one machine).
  // Its images still come in real time: the pacing is on the dataset's time.
  double clock_ = 0.0;
  std::optional<DdsTransport> transport_;
  std::optional<RosPublisher> ros_;
  std::optional<LiveCamera> camera_;  // live: the image stream
  std::vector<obs::EstimateMessage> inbox_;
  NodeTimes times_;
  NodeSummary summary_;
};

// The camera's source: its dataset's, or live (TopicNetwork, `topics` set to it).
std::unique_ptr<sources::NetworkSource> open_source(const fs::path& dataset, const NodeSettings& o,
                                                    sources::TopicNetwork*& topics) {
  if (!o.live) return sources::open_dataset_source(dataset, o.camera_id, o.run.keep_going);
  auto t = std::make_unique<sources::TopicNetwork>(dataset, o.camera_id);
  topics = t.get();
  return t;
}

// The index of camera `id` in a source a camera process can run.
int camera_index(const sources::NetworkSource& source, int id) {
  sources::require_static_cameras(source, "a camera process (netvmo launch, node)");
  sources::require_single_target(source, "a camera process (netvmo launch, node)");
  const int self = source.network().index_of(id);
  if (self < 0)
    throw InputError(source.network().source + ": cameras: no camera " + std::to_string(id));
  return self;
}

Node::Node(const fs::path& dataset, const NodeSettings& o)
    : o_(o),
      live_(o.live.has_value()),
      async_(o.dds.mode == Mode::async),
      source_(open_source(dataset, o, topics_)),
      cfg_(source_->network()),
      self_(camera_index(*source_, o.camera_id)),
      si_(static_cast<size_t>(self_)),
      graph_(run::network_graph(cfg_)) {
  const size_t n = cfg_.cameras.size();
  for (const auto& c : cfg_.cameras) labels_.push_back(c.id);

  // The same settings, rounds and front end as the in-process run (run_images).
  rs_ = o.run.runner;
  rs_.tag_size = cfg_.target().size;
  // n: zero-offset's hold threshold 1/(2n) (ObserverSettings::hold_threshold) needs it.
  net_.emplace(self_, graph_.neighbors(self_), run::camera_observer_settings(rs_, false),
               static_cast<int>(n));
  ind_.emplace(self_, std::vector<int>{}, run::camera_observer_settings(rs_, true),
               static_cast<int>(n));
  for (auto* c : {&*net_, &*ind_}) {
    c->set_camera_pose(cfg_.cameras[si_].g_wi);
    c->reset(run::paper_initial_estimate());
    c->set_initialized(rs_.init == run::InitMode::Paper);
  }
  net_->set_incarnation(static_cast<std::uint64_t>(
      std::chrono::system_clock::now().time_since_epoch() / std::chrono::nanoseconds(1)));
  check_modes();
  dt_ = 1.0 / cfg_.fps;
  dt_own_ = 1.0 / cfg_.camera_fps(si_);
  run::checked_rounds(dt_, o.run.runner.k_e, o.run.runner.k_s, graph_.max_degree(),
                      o.run.runner.rounds);
  own_frames_ = source_->camera_frame_count(si_);

  frontend::DetectorSettings ds = o.run.detector;
  targets_ = {cfg_.target()};  // the first target only
  frontend::set_targets(ds, targets_);
  const int workers = std::max(1, std::min<int>(o.run.workers, static_cast<int>(n)));
  ds.nthreads = std::max(1, ds.nthreads / workers);
  front_end_.emplace(ds, o.run.tracking);
  count_frames();
  clock_ = o.dds.clock_offset_s;
  if (clock_ != 0.0 && !async_)
    throw InputError("--clock-offset: lock-step needs one clock for every camera (--mode async)");
}

void Node::check_modes() const {
  if (live_ && !async_)
    throw InputError(
        "a live camera (--live, --image-topic) runs on its images' stamps: --mode "
        "async");
  if (!async_ && cfg_.camera_fps(si_) != cfg_.fps)
    throw InputError(cfg_.source + ": cameras[" + std::to_string(si_) + "].fps: camera " +
                     std::to_string(o_.camera_id) +
                     " runs at its own frame rate; lock-step needs one clock for every camera "
                     "(use --mode async)");
}

double Node::frame_length(int k) {
  if (!async_) return dt_;
  const bool next = camera_ ? camera_->wait_frame(k + 1, 0.0) : k + 1 < own_frames_;
  const double len = next ? frame_time(k + 1) - frame_time(k) : dt_own_;
  return len > 0 ? len : dt_own_;  // (a missing image without a time)
}

void Node::count_frames() {
  frames_ = o_.frames ? *o_.frames
            : live_   ? std::numeric_limits<int>::max()
                      : source_->frame_count();
  if (o_.run.max_frames) frames_ = std::min(frames_, *o_.run.max_frames);
  dataset_frames_ = live_ ? 0 : frames_;
  // Async: the run covers `frames` frames of the dataset's clock from the earliest camera's
  // first image (t0); this camera runs its own images within that span.
  if (async_ && !live_) {
    t0_ = source_->frame_time(0, 0);
    for (size_t i = 1; i < cfg_.cameras.size(); ++i) t0_ = std::min(t0_, source_->frame_time(i, 0));
    const double t_end = t0_ + frames_ * dt_;
    int own = 0;
    while (own < own_frames_ && frame_time(own) < t_end - 1e-9) ++own;
    frames_ = own;
  }
}

// The transport, matched with every neighbour's writer (at most dds.timeout_s), and the camera's
// ROS 2 publisher with the readers it must wait for.
void Node::connect() {
  DdsSettings dds = o_.dds;
  dds.graph_digest = graph_digest(labels_, cfg_.edges);
  transport_.emplace(self_, graph_.neighbors(self_), labels_, dds);
  const auto t_discovery = Clock::now();
  times_.discovered = transport_->wait_for_writers(static_cast<int>(graph_.neighbors(self_).size()),
                                                   o_.dds.timeout_s);
  // Setup (reading, the front end, the participant) and discovery (every neighbour's writer
  // matched), for the record.
  times_.setup_s = std::chrono::duration<double>(t_discovery - t_start_).count();
  times_.discovery_s = std::chrono::duration<double>(Clock::now() - t_discovery).count();
  if (o_.publish_ros_pose) ros_.emplace(transport_->participant(), o_.camera_id);
  if (ros_ && o_.ros_wait_readers > 0 &&
      !ros_->wait_pose_readers(o_.ros_wait_readers, o_.dds.timeout_s)) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "rt/netvmo/camera_%d/average_pose: %d reader(s) did not come within %g s "
                  "(--ros-wait-readers)",
                  o_.camera_id, o_.ros_wait_readers, o_.dds.timeout_s);
    throw InputError(buf);
  }
}

// The common start (seconds since the epoch), if there is one: the settings', the start file's
// once this node is ready (async), or a live camera's first image (its clock then starts there).
std::optional<double> Node::start() {
  std::optional<double> start_epoch = o_.start_epoch;
  // Live: the image topic is read once the node is set up and matched with its neighbours.
  if (live_)
    camera_.emplace(o_.dds.domain, *topics_, si_, *o_.live,
                    o_.dds.security ? &*o_.dds.security : nullptr);
  if (async_ && o_.start_file) {  // ready: tell the launcher, then wait for the common start
    io::write_file_atomic(node_ready_file(*o_.start_file, o_.camera_id), "ready\n");
    if (!live_) start_epoch = read_start(*o_.start_file, o_.dds.timeout_s);
  }
  if (live_) {
    camera_->wait_frame(0, o_.dds.timeout_s);
    t0_ = frame_time(0);
    start_epoch = camera_->first_wall() + o_.live->lag_s;
  }
  return start_epoch;
}

// Frame k through the front end: its observation (a frame that cannot be read, with
// --keep-going, is blind and warned about).
const frontend::Observation& Node::observe(int k) {
  cv::Mat image;
  if (const auto error = run::observe_camera(*source_, si_, k, *front_end_, track_, targets_,
                                             o_.run.keep_going, image, cams_)) {
    if (!o_.run.keep_going) std::rethrow_exception(error);
    try {
      std::rethrow_exception(error);
    } catch (const InputError& e) {
      summary_.warnings.push_back(std::string(e.what()) + " (camera " +
                                  std::to_string(o_.camera_id) + " blind at frame " +
                                  std::to_string(k) + ")");
    }
  }
  return cams_[0];
}

// Frame k's exchange rounds (obs exchange.hpp), as NetworkedObserver runs them in one process,
// and the independent baseline's steps.
void Node::exchange_rounds(int k, const obs::Measurement& z, double start, obs::JoinHold& join,
                           obs::Transport& exchange) {
  obs::CameraObserver& net = *net_;
  obs::Measurement blind;  // what a restarted node holds until it has heard its neighbours
  net.set_measurement(join.held ? blind : z);
  ind_->set_measurement(z);
  const double t = frame_time(k), len = frame_length(k);
  const int N = substeps(len, net), N_ind = substeps(len, *ind_);
  const double h = len / N, h_ind = len / N_ind;
  for (int r = 0; r < N; ++r) {
    const double tr = t + r * h;
    if (join.release(net, tr))
      net.set_measurement(z);
    else if (join.held)
      ++summary_.join_rounds;
    if (async_) sleep_until_epoch(start + (tr - t0_) / o_.speed);
    // Lock-step neighbours wait for every round's message; an async node publishes nothing
    // while it has no estimate. Async: the latest value of each neighbour is forgotten once
    // older than the staleness bound (its stamp on this node's clock: DdsTransport::receive).
    const auto round_start = Clock::now();
    if (!async_ || net.initialized()) obs::send_estimate(net, *transport_, tr + clock_);
    const obs::TakeReport taken = obs::take_estimates(
        net, exchange, inbox_,
        async_ ? std::optional<obs::Staleness>({tr + clock_, o_.stale_s}) : std::nullopt);
    (r == 0 ? times_.first_round_us : times_.round_us)
        .push_back(std::chrono::duration<double, std::micro>(Clock::now() - round_start).count());
    summary_.forgotten += taken.forgotten;
    if (join.may_step(net, tr)) net.step(h);
  }
  for (int r = 0; r < N_ind; ++r) ind_->step(h_ind);
}

NodeSummary Node::run(const fs::path& out_dir) {
  connect();
  io::ensure_directory(out_dir);
  const NodeFiles files = node_files(out_dir, o_.camera_id);
  const std::optional<double> start_epoch = start();
  // The camera's ROS 2 topics (RosPublisher): its pose in the rig once, on rt/tf_static.
  if (ros_)
    ros_->tf_static(
        {run::camera_transform(o_.camera_id, frame_time(0) + clock_, cfg_.cameras[si_].g_wi)});
  summary_.notes = source_->notes();
  summary_.substeps = substeps(dt_own_, *net_);
  const double start = start_epoch ? *start_epoch : epoch_seconds();
  if (async_ && !(o_.speed > 0)) throw InputError("--speed must be > 0");
  // A node started after the common start (a restart) joins at its next image, on schedule.
  int first = 0;
  if (async_ && start_epoch && !live_) {
    const double now_cam = t0_ + (epoch_seconds() - start) * o_.speed;
    while (first < frames_ && frame_time(first) < now_cam) ++first;
  }
  summary_.first_frame = first;
  RowJournal csv(files.csv, kNodeJournalHeader, o_.resume, first);
  // The effective graph as this camera sees it: after each frame, the neighbours whose estimate
  // is in its mutual term (heard, initialised, not forgotten as stale).
  RowJournal links(files.links, "frame,t,neighbours", o_.resume, first);
  // A node that joins late (a restart) starts from its neighbours, like a blind camera, so that
  // its first estimate is theirs and none of them jumps: it steps, and uses its own measurement,
  // once it has heard every neighbour, or, if one stays silent, after the staleness bound.
  obs::JoinHold join{async_ && first > 0 && rs_.init == run::InitMode::Pnp,
                     frame_time(first) + o_.stale_s};
  // Async: the faults injected on this side (--drop, --delay), between DDS and the observer.
  FaultyTransport faulty(*transport_, o_.drop, o_.delay_ms / 1000.0,
                         o_.seed * 1000003ULL + static_cast<std::uint64_t>(o_.camera_id),
                         epoch_seconds);
  obs::Transport& exchange = async_ ? static_cast<obs::Transport&>(faulty) : *transport_;
  int k = first;
  for (; k < frames_ && (!camera_ || camera_->wait_frame(k, 0.0)); ++k) {
    const frontend::Observation& cam = observe(k);
    const obs::Measurement z =
        run::measurement_of(cam, source_->target_truth(k), source_->camera_truth(si_, k));
    if (net_->error_model().input() == obs::MeasurementInput::true_pose && z.delta && !z.g_io_true)
      throw InputError("the " + std::string(net_->error_model().name()) +
                       " error model needs ground truth (rendered data)");
    exchange_rounds(k, z, start, join, exchange);
    const double t = frame_time(k) + clock_;
    csv.row(node_journal_row({k, t, cam, net_->initialized(), ind_->initialized(),
                              net_->estimate_world(), ind_->estimate_world()}));
    links.row(links_row(k, t, *net_, labels_));
    csv.flush();
    links.flush();
    if (ros_) publish_frame(*ros_, o_.camera_id, t, cam, *net_);
  }
  // Lock-step neighbours still wait for our last round; async ones take what has arrived (and a
  // killed neighbour would never acknowledge).
  transport_->flush(async_ ? 0.2 : 5.0);
  csv.commit();
  links.commit();
  finish(k, faulty);
  const nlohmann::json j =
      node_json(o_, summary_, frames_, dataset_frames_, camera_ ? &*camera_ : nullptr, times_,
                transport_->clock(), graph_.neighbors(self_), labels_, clock_);
  io::write_file_atomic(files.json, j.dump(2) + "\n");
  return summary_;
}

// The summary once the last frame (before frame k) is done, while the participants, and so
// their sockets, are open.
void Node::finish(int k, const FaultyTransport& faulty) {
  if (live_) frames_ = k;
  if (track_.resampling)
    if (auto w = frontend::resampling_warning(o_.camera_id, *track_.resampling))
      summary_.warnings.push_back(*w);
  summary_.kernel_drops = udp_drops_of_this_process();
  if (live_ && summary_.kernel_drops.value_or(0) > 0)
    summary_.warnings.push_back("camera " + std::to_string(o_.camera_id) + ": " +
                                kernel_drops_consequence(*summary_.kernel_drops));
  summary_.frames = frames_;
  summary_.stats = transport_->stats();
  summary_.stats.dropped = faulty.dropped();
  summary_.refused = net_->refused();
  summary_.seconds = std::chrono::duration<double>(Clock::now() - t_start_).count();
}

}  // namespace

NodeFiles node_files(const fs::path& dir, int camera_id) {
  const std::string s = "node_" + std::to_string(camera_id);
  return {dir / (s + ".csv"), dir / (s + "_links.csv"), dir / (s + ".json"), dir / (s + ".log")};
}

fs::path node_ready_file(const fs::path& start_file, int camera_id) {
  return start_file.parent_path() / ("node_" + std::to_string(camera_id) + ".ready");
}

NodeSummary run_node(const fs::path& dataset, const fs::path& out_dir, const NodeSettings& o) {
  return Node(dataset, o).run(out_dir);
}

}  // namespace netvmo::net
