#include <algorithm>
#include <cmath>

#include "netvmo/observer/observer_settings.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/node_journal.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using obs::SE3;

namespace {

// One clock: row k of every node is frame k of the dataset. With allow_gaps a frame a node has
// no row for (not running: killed, or before its restart) is blind and uninitialised.
std::vector<const NodeRow*> by_frame(const std::vector<NodeRow>& rows, const fs::path& file,
                                     int frames, bool allow_gaps) {
  std::vector<const NodeRow*> out(static_cast<size_t>(frames), nullptr);
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
  std::vector<std::vector<NodeRow>> rows;
  std::vector<fs::path> files;
  for (const auto& c : net.cameras) {
    files.push_back(node_files(nodes_dir, c.id).csv);
    rows.push_back(read_node_journal(files.back(), allow_gaps || own_clocks));
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
  std::vector<std::vector<const NodeRow*>> held(n);
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

  const NodeRow none;  // blind and uninitialised
  for (int k = 0; k < frames; ++k) {
    run::FrameRecord r;
    r.frame = k;
    r.t = k * dt;  // since t0
    // Own clocks: the truth at the grid time (target.csv holds every image time of any camera).
    r.g_wo_true = own_clocks ? source.target_truth_at(grid.time(k)) : source.target_truth(k);
    r.cameras.resize(n);
    std::vector<frontend::Observation> cams(n);
    for (size_t i = 0; i < n; ++i) {
      const NodeRow* p = held[i][static_cast<size_t>(k)];
      const NodeRow& row = p ? *p : none;
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
