#include "netvmo/pipeline/run/sweep.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/run/run_report.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;

namespace {
// The sweep replays one input per static camera and frame at 1 / fps.
void require_sweepable(const sources::NetworkSource& source) {
  sources::require_static_cameras(source, "netvmo sweep");
  sources::require_single_target(source, "netvmo sweep");
  if (!source.network().target().bundle.empty())
    throw InputError(source.network().source +
                     ": target.bundle: netvmo sweep does not take tag bundles (its inputs cache "
                     "holds one tag's 8 features); use netvmo run");
  auto m = sources::clock_mismatch(source);
  if (!m) m = sources::irregular_clock(source);
  if (m)
    throw InputError(*m +
                     ": netvmo sweep replays the cameras on one clock at the dataset's fps "
                     "(cameras on their own clocks run with `netvmo run`)");
}
}  // namespace

RecordedInputs record_inputs(sources::NetworkSource& source, const ImageRunSettings& options) {
  require_sweepable(source);
  const auto result = run_images(source, options);
  const size_t n = source.network().cameras.size();
  std::vector<std::optional<SE3>> true_wi(n);
  for (size_t i = 0; i < n; ++i) true_wi[i] = source.camera_truth(i, 0);
  RecordedInputs in;
  in.dt = 1.0 / source.network().fps;
  for (size_t k = 0; k < result.frames.size(); ++k) {
    in.targets.push_back(source.target_truth(static_cast<int>(k)));
    in.frames.push_back(measurements_of(result.frames[k], in.targets.back(), true_wi));
  }
  return in;
}

namespace {

std::string cache_header(const sources::NetworkSource& source, const ImageRunSettings& o,
                         size_t frames) {
  char b[512];
  std::snprintf(b, sizeof b,
                "# netvmo inputs v1: dataset %s, %zu frames, %zu cameras, decimate %g, refine %s, "
                "track %d",
                source.name().c_str(), frames, source.network().cameras.size(),
                o.detector.quad_decimate, frontend::to_string(o.detector.refinement),
                o.tracking.enabled ? 1 : 0);
  return b;
}

size_t expected_frames(const sources::NetworkSource& source, const ImageRunSettings& o) {
  int frames = source.frame_count();
  if (o.max_frames) frames = std::min(frames, *o.max_frames);
  return static_cast<size_t>(frames);
}

}  // namespace

void write_inputs_cache(const fs::path& file, const sources::NetworkSource& source,
                        const ImageRunSettings& options, const RecordedInputs& in) {
  io::AtomicFile f(file);
  f << cache_header(source, options, in.frames.size()) << '\n';
  f << "frame,camera_index,delta,f0,f1,f2,f3,f4,f5,f6,f7,pnp,px,py,pz,r00,r01,r02,r10,r11,r12,"
       "r20,r21,r22\n";
  const auto num = [&](double v) { f << ',' << io::exact_text(v); };
  for (size_t k = 0; k < in.frames.size(); ++k)
    for (size_t i = 0; i < in.frames[k].size(); ++i) {
      const auto& z = in.frames[k][i];
      f << k << ',' << i << ',' << (z.delta ? 1 : 0);
      const SE3 g = z.g_io_pnp ? *z.g_io_pnp : SE3::Identity();
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r = g.linear();
      // The number columns: f0..f7, pnp (1 or 0, as %.17g writes them), px..pz, r00..r22.
      Eigen::Matrix<double, 21, 1> cells;
      cells << (z.f.size() == 8 ? z.f : Eigen::VectorXd::Zero(8)), (z.g_io_pnp ? 1.0 : 0.0),
          g.translation(), Eigen::Map<const Eigen::Matrix<double, 9, 1>>(r.data());
      for (const double v : cells) num(v);
      f << '\n';
    }
  f.commit();
}

std::optional<RecordedInputs> read_inputs_cache(const fs::path& file,
                                                const sources::NetworkSource& source,
                                                const ImageRunSettings& options) {
  std::ifstream f(file);
  if (!f) return std::nullopt;
  const size_t frames = expected_frames(source, options);
  const size_t n = source.network().cameras.size();
  std::string line;
  if (!std::getline(f, line) || line != cache_header(source, options, frames)) return std::nullopt;
  std::getline(f, line);  // column names
  RecordedInputs in;
  in.dt = 1.0 / source.network().fps;
  in.frames.assign(frames, std::vector<obs::Measurement>(n));
  require_sweepable(source);
  std::vector<std::optional<SE3>> true_wi(n);
  for (size_t i = 0; i < n; ++i) true_wi[i] = source.camera_truth(i, 0);
  size_t rows = 0;
  for (int lineno = 3; std::getline(f, line); ++lineno) {
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');)
      v.push_back(io::parse_finite(cell).value_or(std::nan("")));
    const bool ok = v.size() == 24 &&
                    std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }) &&
                    v[0] >= 0 && v[0] < frames && v[1] >= 0 && v[1] < n;
    if (!ok)
      throw InputError(file.string() + ": line " + std::to_string(lineno) +
                       ": malformed row (delete the file to detect again)");
    auto& z = in.frames[static_cast<size_t>(v[0])][static_cast<size_t>(v[1])];
    z.delta = v[2] != 0;
    if (z.delta) z.f = Eigen::Map<const Eigen::VectorXd>(&v[3], 8);
    if (v[11] != 0) {
      SE3 g = SE3::Identity();
      g.translation() = obs::Vec3(v[12], v[13], v[14]);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) g.linear()(r, c) = v[15 + 3 * r + c];
      z.g_io_pnp = g;
    }
    ++rows;
  }
  if (rows != frames * n)
    throw InputError(file.string() + ": " + std::to_string(rows) + " rows for " +
                     std::to_string(frames * n) + " (delete the file to detect again)");
  for (size_t k = 0; k < frames; ++k) {
    in.targets.push_back(source.target_truth(static_cast<int>(k)));
    for (size_t i = 0; i < n; ++i)
      if (in.targets.back() && true_wi[i])
        in.frames[k][i].g_io_true = true_wi[i]->inverse() * *in.targets.back();
  }
  return in;
}

SweepContext sweep_context(const io::NetworkConfig& net, const RecordedInputs& in) {
  SweepContext c{network_graph(net), {}, 0.0, 0, {}, 0, false, {}, 0};
  for (const auto& cam : net.cameras) c.g_wi.push_back(cam.g_wi);
  c.W = obs::paper_W(c.graph).value;
  c.diameter = c.graph.diameter();
  if (!in.frames.empty()) {  // the visible set of the last frame, through the true g_io
    std::vector<SE3> fict;
    for (size_t i = 0; i < in.frames.back().size(); ++i) {
      const auto& z = in.frames.back()[i];
      if (z.delta && z.g_io_true) fict.push_back(c.g_wi[i] * *z.g_io_true);
    }
    if (!fict.empty()) c.spread = obs::spread(fict, obs::average_pose(fict));
    c.n_visible = static_cast<int>(fict.size());
    std::vector<SE3> measured;  // the same through the measured g_io (PnP)
    for (size_t i = 0; i < in.frames.back().size(); ++i) {
      const auto& z = in.frames.back()[i];
      if (z.delta && z.g_io_pnp) measured.push_back(c.g_wi[i] * *z.g_io_pnp);
    }
    if (!measured.empty()) c.measured_spread = obs::spread(measured, obs::average_pose(measured));
    c.n_measured = static_cast<int>(measured.size());
  }
  for (const auto& frame : in.frames)
    for (const auto& z : frame) c.truth = c.truth || z.g_io_true.has_value();
  return c;
}

namespace {
// A pair of columns (position [m], orientation [deg]) raised to a pose error where it is larger.
void raise_to(const PoseError& e, double& position_m, double& orientation_deg) {
  position_m = std::max(position_m, e.position);
  orientation_deg = std::max(orientation_deg, e.orientation_deg);
}
}  // namespace

SweepPoint sweep_point(const SweepContext& c, RunnerSettings settings, const RecordedInputs& in) {
  Runner runner(c.graph, c.g_wi, settings);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  SweepPoint p;
  p.k_e = settings.k_e;
  p.k_s = settings.k_s;
  p.rounds = runner.substeps(in.dt);
  p.step_factor = runner.step_factor(in.dt);
  p.eps_p = p.eps_R = p.U_p = p.U_R = p.worst_position_m = p.worst_orientation_deg = nan;
  p.eps_p_measured = p.eps_R_measured = p.disagreement_m = p.disagreement_deg = nan;
  if (!c.truth) p.eps_p_tail = p.eps_R_tail = nan;
  for (size_t k = 0; k < in.frames.size(); ++k)
    runner.process(static_cast<int>(k), k * in.dt, in.dt, in.frames[k], in.targets[k]);
  const auto& h = runner.history();
  const size_t tail = h.size() - h.size() / 4;
  for (size_t k = 0; k < h.size(); ++k) {
    if (!h[k].energies) continue;
    p.eps_p = h[k].eps->eps_p;
    p.eps_R = h[k].eps->eps_R;
    p.U_p = h[k].energies->U_p;
    p.U_R = h[k].energies->U_R;
    if (k >= tail) {
      p.eps_p_tail = std::max(p.eps_p_tail, p.eps_p);
      p.eps_R_tail = std::max(p.eps_R_tail, p.eps_R);
    }
    p.worst_position_m = p.worst_orientation_deg = 0.0;
    for (const auto& cam : h[k].cameras) {
      raise_to(pose_error(cam.est_w, *h[k].g_star), p.worst_position_m, p.worst_orientation_deg);
    }
  }
  // Without truth: against the measured average, between cameras, and from frame to frame.
  for (size_t k = 0; k < h.size(); ++k) {
    const auto& cams = h[k].cameras;
    bool all = !cams.empty();
    std::vector<SE3> est, measured;
    for (const auto& cam : cams) {
      all = all && cam.initialized;
      est.push_back(cam.est_w);
      if (cam.pnp_w) measured.push_back(*cam.pnp_w);
    }
    if (k >= tail && k > 0 && h[k - 1].cameras.size() == cams.size()) {
      for (size_t i = 0; i < cams.size(); ++i) {
        if (!cams[i].initialized || !h[k - 1].cameras[i].initialized) continue;
        raise_to(pose_error(cams[i].est_w, h[k - 1].cameras[i].est_w), p.last_quarter_step_m,
                 p.last_quarter_step_deg);
      }
    }
    if (!all) continue;
    if (h[k].central_w) {
      const obs::EpsLevels eps =
          obs::eps_levels(est, *h[k].central_w, obs::spread(measured, *h[k].central_w),
                          static_cast<int>(measured.size()));
      p.eps_p_measured = eps.eps_p;
      p.eps_R_measured = eps.eps_R;
    }
    if (k + 1 == h.size()) {
      p.disagreement_m = p.disagreement_deg = 0.0;
      for (size_t i = 0; i < est.size(); ++i)
        for (size_t j = i + 1; j < est.size(); ++j) {
          raise_to(pose_error(est[i], est[j]), p.disagreement_m, p.disagreement_deg);
        }
    }
  }
  if (h.size() < 2) p.last_quarter_step_m = p.last_quarter_step_deg = nan;
  const double k_ratio =
      settings.k_s > 0 ? settings.k_e / settings.k_s : std::numeric_limits<double>::infinity();
  p.bound = c.truth ? obs::theorem1_bound(k_ratio, c.spread, c.W, c.diameter, c.n_visible)
                    : obs::Theorem1Bound{nan, nan};
  return p;
}

std::vector<double> parse_gain_list(const std::string& option, const std::string& text,
                                    bool allow_zero) {
  std::vector<double> out;
  std::set<double> seen;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    const auto fail = [&](const std::string& why) {
      throw InputError(option + ": '" + item + "' " + why + " (expected e.g. " + option +
                       " 1,2,5)");
    };
    const auto number = io::parse_finite(item);
    if (!number) fail("is not a number");
    const double v = *number;
    if (v < 0 || (!allow_zero && v == 0)) fail(allow_zero ? "is negative" : "must be positive");
    if (!seen.insert(v).second) fail("is listed twice");
    out.push_back(v);
  }
  if (out.empty() || text.back() == ',')
    throw InputError(option + ": an empty list or item (expected e.g. " + option + " 1,2,5)");
  return out;
}

void write_sweep_csv(const fs::path& file, const std::vector<SweepPoint>& points) {
  io::AtomicFile f(file);
  f << "k_e,k_s,k,rounds,step_factor,eps_p,eps_R,eps_p_last_quarter,eps_R_last_quarter,U_p,U_R,"
       "worst_position_mm,worst_orientation_deg,theorem1_eps_p,theorem1_eps_R,eps_p_measured,"
       "eps_R_measured,disagreement_mm,disagreement_deg,last_quarter_step_mm,"
       "last_quarter_step_deg\n";
  char b[768];
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (i && p.k_e != points[i - 1].k_e) f << '\n';  // one block per k_e (gnuplot's lines)
    std::snprintf(
        b, sizeof b,
        "%g,%g,%.9g,%d,%.4g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,"
        "%.6g,%.6g\n",
        p.k_e, p.k_s, p.k_s > 0 ? p.k_e / p.k_s : std::numeric_limits<double>::infinity(), p.rounds,
        p.step_factor, p.eps_p, p.eps_R, p.eps_p_tail, p.eps_R_tail, p.U_p, p.U_R,
        p.worst_position_m * 1000.0, p.worst_orientation_deg, p.bound.eps_p, p.bound.eps_R,
        p.eps_p_measured, p.eps_R_measured, p.disagreement_m * 1000.0, p.disagreement_deg,
        p.last_quarter_step_m * 1000.0, p.last_quarter_step_deg);
    f << b;
  }
  f.commit();
}

std::vector<SweepColumn> sweep_columns(const std::vector<SweepPoint>& points) {
  using V = double (*)(const SweepPoint&);
  const std::vector<std::pair<const char*, V>> cols = {
      {"eps_p", [](const SweepPoint& p) { return p.eps_p; }},
      {"eps_R", [](const SweepPoint& p) { return p.eps_R; }},
      {"eps_p_last_quarter", [](const SweepPoint& p) { return p.eps_p_tail; }},
      {"eps_R_last_quarter", [](const SweepPoint& p) { return p.eps_R_tail; }},
      {"U_p", [](const SweepPoint& p) { return p.U_p; }},
      {"U_R", [](const SweepPoint& p) { return p.U_R; }},
      {"worst_position_mm", [](const SweepPoint& p) { return p.worst_position_m; }},
      {"worst_orientation_deg", [](const SweepPoint& p) { return p.worst_orientation_deg; }},
      {"theorem1_eps_p", [](const SweepPoint& p) { return p.bound.eps_p; }},
      {"theorem1_eps_R", [](const SweepPoint& p) { return p.bound.eps_R; }},
      {"eps_p_measured", [](const SweepPoint& p) { return p.eps_p_measured; }},
      {"eps_R_measured", [](const SweepPoint& p) { return p.eps_R_measured; }},
      {"disagreement_mm", [](const SweepPoint& p) { return p.disagreement_m; }},
      {"disagreement_deg", [](const SweepPoint& p) { return p.disagreement_deg; }},
      {"last_quarter_step_mm", [](const SweepPoint& p) { return p.last_quarter_step_m; }},
      {"last_quarter_step_deg", [](const SweepPoint& p) { return p.last_quarter_step_deg; }},
  };
  std::vector<SweepColumn> out;
  for (size_t c = 0; c < cols.size(); ++c) {
    bool defined = false;
    for (const auto& p : points) defined = defined || std::isfinite(cols[c].second(p));
    out.push_back({cols[c].first, static_cast<int>(c) + 6, defined});
  }
  return out;
}

}  // namespace netvmo::run
