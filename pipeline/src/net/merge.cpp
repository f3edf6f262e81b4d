#include <cmath>
#include <fstream>
#include <sstream>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/net/node.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using obs::SE3;

namespace {

struct Row {
  run::CameraFrame cam;
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

std::vector<Row> read_node_csv(const fs::path& file, int frames, bool allow_gaps) {
  std::ifstream in(file);
  if (!in && allow_gaps) return std::vector<Row>(static_cast<size_t>(frames));  // never finished
  if (!in) throw InputError(file.string() + ": node output not found");
  std::string line;
  std::getline(in, line);  // header
  std::vector<Row> rows;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    Fields f(line, file, line_no);
    Row r;
    const int k = f.integer();
    if (allow_gaps && k > static_cast<int>(rows.size()) && k < frames)
      rows.resize(static_cast<size_t>(k));  // frames the node was not running: blind
    if (k != static_cast<int>(rows.size())) f.fail("frame " + std::to_string(k) + " out of order");
    f.num();  // t
    r.cam.obs.delta = f.integer() != 0;
    r.cam.read_failed = f.integer() != 0;
    r.cam.obs.status = static_cast<frontend::TargetStatus>(f.integer());
    r.cam.obs.tag_id = f.integer();
    r.cam.obs.hamming = f.integer();
    r.cam.obs.margin = f.num();
    for (auto& c : r.cam.obs.corners_px) {
      c.x = f.num();
      c.y = f.num();
    }
    for (int a = 0; a < 8; ++a) r.cam.obs.f_normalized(a) = f.num();
    const bool pnp = f.integer() != 0;
    const SE3 g_io = f.pose();
    if (pnp) r.cam.g_io_pnp = g_io;
    r.initialized = f.integer() != 0;
    r.est_w = f.pose();
    r.indep = f.integer() != 0;
    r.indep_w = f.pose();
    rows.push_back(std::move(r));
  }
  if (allow_gaps && static_cast<int>(rows.size()) < frames)
    rows.resize(static_cast<size_t>(frames));
  if (static_cast<int>(rows.size()) != frames)
    throw InputError(file.string() + ": " + std::to_string(rows.size()) + " frames, expected " +
                     std::to_string(frames));
  return rows;
}

}  // namespace

run::ImageRunResult merge_nodes(const sources::NetworkSource& provider,
                                const run::ImageRunOptions& options, const fs::path& nodes_dir,
                                int frames, bool allow_gaps) {
  const io::NetworkConfig& net = provider.network();
  const size_t n = net.cameras.size();
  const obs::Graph graph = run::network_graph(net);
  std::vector<std::vector<Row>> rows;
  for (const auto& c : net.cameras)
    rows.push_back(read_node_csv(node_file(nodes_dir, c.id, ".csv"), frames, allow_gaps));

  run::RunnerSettings rs = options.runner;
  rs.tag_size = net.target.size;
  const auto os = run::camera_observer_settings(rs, false);
  const double dt = 1.0 / net.fps;
  run::ImageRunResult result;
  result.warnings = provider.warnings();
  result.substeps = obs::frame_substeps(dt, os, graph.max_degree());
  result.step_factor = dt / result.substeps * (rs.k_e + 2.0 * rs.k_s * graph.max_degree());
  if (auto w = run::step_factor_warning(result.substeps, result.step_factor))
    result.warnings.push_back(*w);
  std::vector<std::optional<SE3>> true_wi(n);
  for (size_t i = 0; i < n; ++i) true_wi[i] = provider.camera_truth(i);
  for (int k = 0; k < frames; ++k) {
    run::FrameRecord r;
    r.frame = k;
    r.t = k * dt;
    r.g_wo_true = provider.target_truth(k);
    r.cameras.resize(n);
    std::vector<run::CameraFrame> cams(n);
    for (size_t i = 0; i < n; ++i) {
      const Row& row = rows[i][static_cast<size_t>(k)];
      cams[i] = row.cam;
      auto& c = r.cameras[i];
      const SE3& g_wi = net.cameras[i].g_wi;
      c.delta = row.cam.obs.delta;
      c.initialized = row.initialized;
      c.est_w = row.est_w;
      if (row.indep) c.indep_w = row.indep_w;
      if (c.delta && row.cam.g_io_pnp) c.pnp_w = g_wi * *row.cam.g_io_pnp;
      if (c.delta && r.g_wo_true && true_wi[i])
        c.fictitious_w = g_wi * (true_wi[i]->inverse() * *r.g_wo_true);  // g_wi g_io,true
    }
    run::evaluate_frame(r);
    result.history.push_back(std::move(r));
    result.frames.push_back(std::move(cams));
  }
  return result;
}

}  // namespace netvmo::net
