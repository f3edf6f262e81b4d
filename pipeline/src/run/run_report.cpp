#include "netvmo/pipeline/run/run_report.hpp"

#include <cmath>

#include "netvmo/pipeline/run/flips.hpp"

#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;
using nlohmann::json;

PoseError pose_error(const obs::SE3& estimate, const obs::SE3& reference) {
  return {(estimate.translation() - reference.translation()).norm(),
          obs::log_so3(reference.linear().transpose() * estimate.linear()).norm() * 180.0 / M_PI};
}

namespace {

// Final and mean error of one estimate stream against one reference stream.
class ErrorStats {
 public:
  void add(const std::optional<obs::SE3>& est, const std::optional<obs::SE3>& ref) {
    if (!est || !ref) return;
    last_ = pose_error(*est, *ref);
    sum_p_ += last_->position;
    sum_r_ += last_->orientation_deg;
    ++count_;
  }
  json to_json() const {
    if (!count_) return nullptr;
    return {{"final_position_m", last_->position},
            {"final_orientation_deg", last_->orientation_deg},
            {"mean_position_m", sum_p_ / count_},
            {"mean_orientation_deg", sum_r_ / count_},
            {"frames", count_}};
  }

 private:
  std::optional<PoseError> last_;
  double sum_p_ = 0, sum_r_ = 0;
  int count_ = 0;
};

json vec3(const obs::Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

}  // namespace

json run_summary(const sources::NetworkSource& source, const ImageRunSettings& options,
                 const ImageRunResult& result, size_t target) {
  const io::NetworkConfig& net = source.network();
  const size_t n = net.cameras.size();
  const ImageRunResult& tr = result.target(target);
  const auto& h = tr.history;
  json s;
  s["dataset"] = source.name();
  s["frames"] = h.size();
  s["fps"] = net.fps;
  // The files' clock: t = the dataset's time less this, or (null) t = frame / fps.
  s["time_origin_s"] = result.time_origin_s ? json(*result.time_origin_s) : json(nullptr);
  s["estimator"] = options.runner.estimator;
  s["k_e"] = options.runner.k_e;
  s["k_s"] = options.runner.k_s;
  s["error"] = options.runner.error_model;
  s["init"] = run::to_string(options.runner.init);
  if (options.transport.kind != TransportSettings{}.kind) {  // recorded when not the default
    s["transport"] = {{"kind", options.transport.kind}};
    const auto values = transport_values(options.transport);
    for (const auto& p : transport_kinds().find(options.transport.kind).parameters()) {
      const double v = values.at(p.name);
      s["transport"][p.name] = p.integer ? json(static_cast<std::uint64_t>(v)) : json(v);
    }
  }
  if (source.cameras_move())  // recorded for moving cameras (cameras.csv) only
    s["camera_velocity"] = options.ignore_camera_velocity
                               ? "ignored (--ignore-camera-velocity: V_wi = 0)"
                               : "V_wi = log(g_wi(t_k)^-1 g_wi(t_k+1)) / dt, held over the frame";
  s["rounds_per_frame"] = result.substeps;
  s["step_factor"] = result.step_factor;  // h (k_e + 2 k_s d_max): < 2 stable
  s["reference"] =
      "g_star: average (eq:g_ave) of the fictitious target poses g_wi g_io,true of the cameras "
      "that detect the tag in that frame; true: the true target pose";
  if (result.union_of_timestamps) {  // cameras on their own clocks (netvmo run)
    s["clock"] =
        "union of timestamps: the observer advanced on the union of every camera's image times "
        "in time order, integrating over the real elapsed time between them; each camera's "
        "detection and measurement held until its next image; estimates.csv: one row per camera "
        "image at its time; energies, eps and errors on the regular grid t0 + k / fps against "
        "g*(t) at each grid time";
    s["grid"] = {{"t0", h.empty() ? 0.0 : h.front().t}, {"dt", 1.0 / net.fps}};
  }

  std::vector<ErrorStats> net_star(n), net_true(n), ind_star(n), ind_true(n), pnp_star(n),
      pnp_true(n), pnp_own(n);
  const auto& compared = options.runner.compare_estimators;
  std::vector<std::vector<ErrorStats>> cmp_star(n, std::vector<ErrorStats>(compared.size())),
      cmp_true = cmp_star;
  ErrorStats central_star, central_true;
  std::vector<int> seen(n, 0), failed(n, 0);
  // Pose sequences for the flip counts (flips.hpp): each camera's PnP (frames it detects) and
  // its networked estimate (frames it has one), and the true target pose.
  std::vector<std::vector<std::optional<obs::SE3>>> pnp_seq(n), net_seq(n);
  std::vector<std::optional<obs::SE3>> true_seq;
  for (size_t k = 0; k < h.size(); ++k) {
    const auto& r = h[k];
    for (size_t i = 0; i < n; ++i) {
      const auto& c = r.cameras[i];
      seen[i] += c.delta;
      failed[i] += tr.frames[k][i].read_failed;
      const std::optional<obs::SE3> est =
          c.initialized ? std::optional<obs::SE3>(c.est_w) : std::nullopt;
      pnp_seq[i].push_back(c.pnp_w);
      net_seq[i].push_back(est);
      net_star[i].add(est, r.g_star);
      net_true[i].add(est, r.g_wo_true);
      ind_star[i].add(c.indep_w, r.g_star);
      ind_true[i].add(c.indep_w, r.g_wo_true);
      pnp_star[i].add(c.pnp_w, r.g_star);
      pnp_true[i].add(c.pnp_w, r.g_wo_true);
      pnp_own[i].add(c.pnp_w, c.fictitious_w);  // measurement error: PnP vs the true g_io
      for (size_t e = 0; e < c.compare_w.size(); ++e) {
        cmp_star[i][e].add(c.compare_w[e], r.g_star);
        cmp_true[i][e].add(c.compare_w[e], r.g_wo_true);
      }
    }
    true_seq.push_back(r.g_wo_true);
    central_star.add(r.central_w, r.g_star);
    central_true.add(r.central_w, r.g_wo_true);
  }
  json cams = json::array();
  for (size_t i = 0; i < n; ++i) {
    json c;
    c["id"] = net.cameras[i].id;
    c["seen_fraction"] = h.empty() ? 0.0 : static_cast<double>(seen[i]) / h.size();
    c["unreadable_frames"] = failed[i];
    c["networked"] = {{"vs_g_star", net_star[i].to_json()}, {"vs_true", net_true[i].to_json()}};
    c["independent"] = {{"vs_g_star", ind_star[i].to_json()}, {"vs_true", ind_true[i].to_json()}};
    c["pnp"] = {{"vs_g_star", pnp_star[i].to_json()},
                {"vs_true", pnp_true[i].to_json()},
                {"vs_own_fictitious_target", pnp_own[i].to_json()}};
    for (size_t e = 0; e < compared.size(); ++e)  // further networked estimators, same gains
      c["compared"][compared[e]] = {{"vs_g_star", cmp_star[i][e].to_json()},
                                    {"vs_true", cmp_true[i][e].to_json()}};
    const double thr = options.flips.threshold_deg;
    const auto flips = [](const FlipCount& f) {
      return json{{"flips", f.flips}, {"pairs", f.pairs}, {"rate", f.rate()}};
    };
    c["flips"] = {{"pnp", flips(count_flips(pnp_seq[i], thr))},
                  {"networked", flips(count_flips(net_seq[i], thr))}};
    if (!h.empty()) {
      const auto& last = h.back().cameras[i];
      c["final_estimate"] = {{"p", vec3(last.est_w.translation())},
                             {"r", vec3(obs::rotvec(last.est_w))}};
    }
    cams.push_back(c);
  }
  s["cameras"] = cams;
  s["flip_threshold_deg"] = options.flips.threshold_deg;
  // The target's largest true rotation per frame (null without ground truth), to check that the
  // flip threshold exceeds it.
  s["target_max_step_deg"] =
      count_flips(true_seq, 0.0).pairs ? json(max_step_deg(true_seq)) : json(nullptr);
  s["centralized_pnp_average"] = {{"vs_g_star", central_star.to_json()},
                                  {"vs_true", central_true.to_json()}};
  // Energies and epsilon-levels at the last frame with ground truth, and the sup of the
  // epsilon-levels over the last quarter of the run.
  json energy = nullptr;
  double eps_p_tail = 0, eps_R_tail = 0;
  for (size_t k = 0; k < h.size(); ++k) {
    if (!h[k].energies) continue;
    energy = {{"U_p", h[k].energies->U_p},
              {"U_R", h[k].energies->U_R},
              {"eps_p", h[k].eps->eps_p},
              {"eps_R", h[k].eps->eps_R},
              {"frame", h[k].frame}};
    if (h[k].energies_indep) {
      energy["U_p_independent_observers"] = h[k].energies_indep->U_p;
      energy["U_R_independent_observers"] = h[k].energies_indep->U_R;
    }
    for (size_t e = 0; e < h[k].energies_compare.size(); ++e)
      if (h[k].energies_compare[e]) {
        energy["U_p_" + compared[e]] = h[k].energies_compare[e]->U_p;
        energy["U_R_" + compared[e]] = h[k].energies_compare[e]->U_R;
      }
    if (k >= h.size() - h.size() / 4) {
      eps_p_tail = std::max(eps_p_tail, h[k].eps->eps_p);
      eps_R_tail = std::max(eps_R_tail, h[k].eps->eps_R);
    }
  }
  s["final"] = energy;
  s["eps_p_last_quarter"] = energy.is_null() ? json(nullptr) : json(eps_p_tail);
  s["eps_R_last_quarter"] = energy.is_null() ? json(nullptr) : json(eps_R_tail);
  s["timing"] = {
      {"seconds", result.seconds},
      {"front_end_seconds", result.seconds_front_end},
      {"observer_seconds", result.seconds_observer},
      // Summed over the front end's worker threads.
      {"reading_seconds", result.seconds_reading},
      {"search_seconds", result.seconds_stages.search},
      {"refinement_seconds", result.seconds_stages.refinement},
      {"check_seconds", result.seconds_stages.check},
      {"network_frames_per_second", result.seconds > 0 ? h.size() / result.seconds : 0.0}};
  s["warnings"] = result.warnings;
  s["target"] = net.targets.at(target).id;
  return s;
}

namespace {
// The keys of a summary that belong to one target (the others describe the whole run).
const char* const kPerTargetKeys[] = {"target",
                                      "cameras",
                                      "target_max_step_deg",
                                      "centralized_pnp_average",
                                      "final",
                                      "eps_p_last_quarter",
                                      "eps_R_last_quarter"};
}  // namespace

json run_summary(const sources::NetworkSource& source, const ImageRunSettings& options,
                 const ImageRunResult& result) {
  json s = run_summary(source, options, result, 0);
  if (result.target_count() == 1) return s;
  json targets = json::array();
  for (size_t j = 0; j < result.target_count(); ++j) {
    const json sj = j == 0 ? s : run_summary(source, options, result, j);
    json t;
    for (const char* key : kPerTargetKeys) t[key] = sj[key];
    targets.push_back(t);
  }
  for (const char* key : kPerTargetKeys) s.erase(key);
  s["targets"] = targets;
  return s;
}

json write_run_outputs(const fs::path& dir, const sources::NetworkSource& source,
                       const ImageRunSettings& options, const ImageRunResult& result,
                       const std::optional<json>& g_star_localisation) {
  io::ensure_directory(dir);
  const io::NetworkConfig& net = source.network();
  const size_t n = net.cameras.size();
  // Several targets: a `target` column (the primary tag's id) after t, rows target by target.
  const bool several = result.target_count() > 1;
  const auto target_cell = [&](size_t j) {
    return several ? "," + std::to_string(net.targets[j].id) : std::string();
  };
  const std::string target_col = several ? ",target" : "";
  {
    io::AtomicFile f(dir / "estimates.csv");
    f << (several ? io::kEstimatesTargetsHeader : io::kEstimatesHeader) << '\n';
    const auto row = [&](int frame, double t, size_t j, size_t i, bool delta, bool initialized,
                         const obs::SE3& est_w) {
      f << frame << ',' << t << target_cell(j) << ',' << net.cameras[i].id << ','
        << (delta ? 1 : 0);
      if (initialized) {
        const obs::Vec3 p = est_w.translation(), w = obs::rotvec(est_w);
        f << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << w.x() << ',' << w.y() << ','
          << w.z();
      } else {
        f << ",,,,,,";
      }
      f << '\n';
    };
    for (size_t j = 0; j < result.target_count(); ++j) {
      const ImageRunResult& tr = result.target(j);
      if (!tr.own_estimates.empty()) {  // cameras on their own clocks: their own rows
        for (const auto& e : tr.own_estimates)
          row(e.frame, e.t, j, e.camera, e.delta, e.initialized, e.est_w);
      } else {
        for (const auto& r : tr.history)
          for (size_t i = 0; i < n; ++i)
            row(r.frame, r.t, j, i, r.cameras[i].delta, r.cameras[i].initialized,
                r.cameras[i].est_w);
      }
    }
    f.commit();
  }
  {
    io::AtomicFile f(dir / "energies.csv");
    f << "frame,t" << target_col << ",U_p,U_R\n";
    for (size_t j = 0; j < result.target_count(); ++j)
      for (const auto& r : result.target(j).history)
        if (r.energies)
          f << r.frame << ',' << r.t << target_cell(j) << ',' << r.energies->U_p << ','
            << r.energies->U_R << '\n';
    f.commit();
  }
  {
    io::AtomicFile f(dir / "errors.csv");
    f << "frame,t" << target_col;
    for (const auto& c : net.cameras)
      f << ",cam" << c.id << "_position_mm,cam" << c.id << "_orientation_deg";
    f << '\n';
    for (size_t j = 0; j < result.target_count(); ++j)
      for (const auto& r : result.target(j).history) {
        if (!r.g_star) continue;
        f << r.frame << ',' << r.t << target_cell(j);
        for (size_t i = 0; i < n; ++i) {
          if (r.cameras[i].initialized) {
            const auto e = pose_error(r.cameras[i].est_w, *r.g_star);
            f << ',' << e.position * 1000.0 << ',' << e.orientation_deg;
          } else {
            f << ",,";
          }
        }
        f << '\n';
      }
    f.commit();
  }
  json s = run_summary(source, options, result);
  if (g_star_localisation) s["g_star_localisation"] = *g_star_localisation;
  io::write_file_atomic(dir / "summary.json", s.dump(2) + "\n");
  return s;
}

}  // namespace netvmo::run
