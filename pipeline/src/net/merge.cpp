#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "netvmo/observer/observer_settings.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/net/node.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using obs::SE3;

namespace {

struct Row {
  int frame = 0;
  double t = 0.0;
  frontend::Observation cam;
  bool initialized = false, indep = false;
  SE3 est_w = SE3::Identity(), indep_w = SE3::Identity();
};

class Fields {
 public:
  Fields(const std::string& line, const fs::path& file, int line_no)
      : file_(file), line_no_(line_no) {
    std::stringstream s(line);
    std::string f;
    while (std::getline(s, f, ',')) f_.push_back(f);
  }
  size_t size() const { return f_.size(); }
  double num() {
    if (k_ >= f_.size()) fail("too few fields");
    char* end = nullptr;
    const double v = std::strtod(f_[k_].c_str(), &end);
    if (f_[k_].empty() || *end) fail("field " + std::to_string(k_ + 1) + " is not a number");
    ++k_;
    return v;
  }
  int integer() { return static_cast<int>(num()); }
  SE3 pose() {
    SE3 g = SE3::Identity();
    for (int r = 0; r < 3; ++r) g.translation()(r) = num();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) g.linear()(r, c) = num();
    return g;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_.string() + ":" + std::to_string(line_no_) + ": " + what);
  }

 private:
  std::vector<std::string> f_;
  size_t k_ = 0;
  fs::path file_;
  int line_no_;
};

// A node's rows in the order written (frames strictly increasing). A node killed for good never
// renamed its output: its finished frames are in the .partial file (only with allow_missing).
std::vector<Row> read_node_csv(fs::path file, bool allow_missing) {
  if (!fs::exists(file) && allow_missing) {
    file = partial_path(file);
    if (!fs::exists(file)) return {};  // never ran a frame
  }
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": node output not found");
  std::string line;
  std::getline(in, line);  // header
  std::vector<Row> rows;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    if (in.eof() && allow_missing) break;  // a .partial's last line cut off by the kill
    Fields f(line, file, line_no);
    Row r;
    r.frame = f.integer();
    if (!rows.empty() && r.frame <= rows.back().frame)
      f.fail("frame " + std::to_string(r.frame) + " out of order");
    r.t = f.num();
    r.cam.delta = f.integer() != 0;
    r.cam.read_failed = f.integer() != 0;
    r.cam.status = static_cast<frontend::TargetStatus>(f.integer());
    r.cam.tag_id = f.integer();
    r.cam.hamming = f.integer();
    r.cam.margin = f.num();
    for (auto& c : r.cam.corners_px) {
      c.x = f.num();
      c.y = f.num();
    }
    for (int a = 0; a < 8; ++a) r.cam.f_normalized(a) = f.num();
    const bool pnp = f.integer() != 0;
    const SE3 g_io = f.pose();
    if (pnp) r.cam.g_io_pnp = g_io;
    r.initialized = f.integer() != 0;
    r.est_w = f.pose();
    r.indep = f.integer() != 0;
    r.indep_w = f.pose();
    rows.push_back(std::move(r));
  }
  return rows;
}

// One clock: row k of every node is frame k of the dataset. With allow_gaps a frame a node has
// no row for (not running: killed, or before its restart) is blind and uninitialised.
std::vector<const Row*> by_frame(const std::vector<Row>& rows, const fs::path& file, int frames,
                                 bool allow_gaps) {
  std::vector<const Row*> out(static_cast<size_t>(frames), nullptr);
  for (const auto& r : rows) {
    if (r.frame >= frames)
      throw InputError(file.string() + ": frame " + std::to_string(r.frame) + ", expected " +
                       std::to_string(frames) + " frames");
    out[static_cast<size_t>(r.frame)] = &r;
  }
  if (!allow_gaps && static_cast<int>(rows.size()) != frames)
    throw InputError(file.string() + ": " + std::to_string(rows.size()) + " frames, expected " +
                     std::to_string(frames));
  return out;
}

}  // namespace

run::ImageRunResult merge_nodes(const sources::NetworkSource& source,
                                const run::ImageRunSettings& options, const fs::path& nodes_dir,
                                int frames, bool allow_gaps,
                                const std::vector<double>& clock_correction) {
  const io::NetworkConfig& net = source.network();
  const size_t n = net.cameras.size();
  const obs::Graph graph = run::network_graph(net);
  // Cameras on their own clocks: each node's rows carry its own images' times, and the merge
  // evaluates on a regular grid (below).
  // A live network (sources::TopicNetwork) has no images: its nodes' rows are the only record of
  // them, each on its camera's stamps.
  const bool live = source.frame_count() == 0;
  const bool own_clocks = live || sources::clock_mismatch(source).has_value();
  std::vector<std::vector<Row>> rows;
  std::vector<fs::path> files;
  for (const auto& c : net.cameras) {
    files.push_back(node_files(nodes_dir, c.id).csv);
    rows.push_back(read_node_csv(files.back(), allow_gaps || own_clocks));
    // Onto the reference clock (ClockAlignment::correction_s).
    if (clock_correction.size() > rows.size() - 1)
      for (auto& r : rows.back()) r.t -= clock_correction[rows.size() - 1];
  }

  run::RunnerSettings rs = options.runner;
  rs.tag_size = net.target().size;
  const auto os = run::camera_observer_settings(rs, false);
  const double dt = 1.0 / net.fps;
  run::ImageRunResult result;
  result.warnings = source.warnings();
  result.substeps = obs::frame_substeps(dt, os, graph.max_degree());
  result.step_factor = run::step_factor(os, dt, result.substeps, graph.max_degree());
  if (auto w = run::step_factor_warning(result.substeps, result.step_factor))
    result.warnings.push_back(*w);

  // held[i][k]: camera i's row at frame k. One clock: its row of frame k. Own clocks: frame k
  // is the grid time t0 + k / fps (t0: the earliest camera's first image), and each camera holds
  // its latest row at or before it; estimates.csv keeps every camera's own rows and times. The
  // merged files count time from t0 (the nodes' files keep the dataset's times).
  std::vector<std::vector<const Row*>> held(n);
  run::TimeGrid grid;
  if (live) {  // the grid of the rows' times, as of the images' elsewhere
    double first = INFINITY, last = -INFINITY;
    for (const auto& r : rows)
      if (!r.empty()) {
        first = std::min(first, r.front().t);
        last = std::max(last, r.back().t);
      }
    if (!std::isfinite(first)) throw InputError(nodes_dir.string() + ": no node ran a frame");
    grid = run::time_grid(first, last, dt, frames);
    frames = grid.frames;
  } else {
    grid = run::time_grid(source, frames);
  }
  const double t0 = own_clocks ? grid.t0 : 0.0;
  if (own_clocks) result.time_origin_s = t0;
  if (own_clocks) {
    result.source_frames.assign(static_cast<size_t>(frames), std::vector<int>(n, -1));
    for (size_t i = 0; i < n; ++i) {
      std::vector<double> times;
      for (const auto& r : rows[i]) times.push_back(r.t);
      for (int k = 0; k < frames; ++k) {
        const int at = run::latest_at_or_before(times, grid.time(k));
        held[i].push_back(at >= 0 ? &rows[i][static_cast<size_t>(at)] : nullptr);
        if (at >= 0) result.source_frames[static_cast<size_t>(k)][i] = rows[i][size_t(at)].frame;
      }
      for (const auto& r : rows[i])
        result.own_estimates.push_back({r.frame, r.t - t0, i, r.cam.delta, r.initialized, r.est_w});
    }
    std::stable_sort(result.own_estimates.begin(), result.own_estimates.end(),
                     [](const run::OwnClockRecord& a, const run::OwnClockRecord& b) {
                       return a.t < b.t || (a.t == b.t && a.camera < b.camera);
                     });
  } else {
    for (size_t i = 0; i < n; ++i) held[i] = by_frame(rows[i], files[i], frames, allow_gaps);
  }

  const Row none;  // blind and uninitialised
  for (int k = 0; k < frames; ++k) {
    run::FrameRecord r;
    r.frame = k;
    r.t = k * dt;  // since t0
    // Own clocks: the truth at the grid time (target.csv holds every image time of any camera).
    r.g_wo_true = own_clocks ? source.target_truth_at(grid.time(k)) : source.target_truth(k);
    r.cameras.resize(n);
    std::vector<frontend::Observation> cams(n);
    for (size_t i = 0; i < n; ++i) {
      const Row* p = held[i][static_cast<size_t>(k)];
      const Row& row = p ? *p : none;
      cams[i] = row.cam;
      auto& c = r.cameras[i];
      const SE3& g_wi = net.cameras[i].g_wi;  // static cameras (moving ones: netvmo run)
      const auto true_wi =
          own_clocks ? source.camera_truth_at(i, grid.time(k)) : source.camera_truth(i, k);
      c.delta = row.cam.delta;
      c.initialized = row.initialized;
      c.est_w = row.est_w;
      if (row.indep) c.indep_w = row.indep_w;
      if (c.delta && row.cam.g_io_pnp) c.pnp_w = g_wi * *row.cam.g_io_pnp;
      if (c.delta && r.g_wo_true && true_wi)
        c.fictitious_w = g_wi * (true_wi->inverse() * *r.g_wo_true);  // g_wi g_io,true
    }
    run::evaluate_frame(r);
    result.history.push_back(std::move(r));
    result.frames.push_back(std::move(cams));
  }
  return result;
}

}  // namespace netvmo::net
