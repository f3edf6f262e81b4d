#include "netvmo/pipeline/run/runner.hpp"

#include <stdexcept>

#include "netvmo/observer/jacobian.hpp"

namespace netvmo::run {

InitMode parse_init_mode(const std::string& s) {
  if (s == "pnp") return InitMode::Pnp;
  if (s == "paper") return InitMode::Paper;
  throw std::invalid_argument("unknown initialisation '" + s + "' (pnp or paper)");
}

const char* to_string(InitMode m) {
  return m == InitMode::Pnp ? "pnp" : "paper";
}

SE3 paper_initial_estimate() {
  SE3 g = SE3::Identity();
  g.translation() = obs::Vec3(0, 0, 1);
  g.linear() = obs::Vec3(1, -1, -1).asDiagonal();
  return g;
}

obs::ObserverSettings camera_observer_settings(const RunnerSettings& s, bool independent) {
  obs::ObserverSettings o;
  o.estimator = independent ? std::string("vmo") : s.estimator;
  o.k_e = s.k_e;
  o.k_s = independent ? 0.0 : s.k_s;
  o.error_model = s.error_model;
  o.features = obs::FeatureModel::square(s.tag_size);
  o.substeps = s.rounds;
  o.init_from_measurement = s.init == InitMode::Pnp;
  o.init_from_neighbours = s.init == InitMode::Pnp && !independent;
  o.min_feature_depth = s.min_feature_depth;
  return o;
}

double step_factor(const obs::ObserverSettings& s, double dt, int substeps, int max_degree) {
  return dt / substeps * obs::estimators().find(s.estimator).rate_bound(s, max_degree);
}

Runner::Runner(const obs::Graph& graph, std::vector<SE3> g_wi, RunnerSettings settings)
    : graph_(graph),
      g_wi_(std::move(g_wi)),
      settings_(settings),
      net_(graph, camera_observer_settings(settings, false)),
      indep_(graph, camera_observer_settings(settings, true)) {
  const auto n = static_cast<size_t>(graph_.size());
  if (g_wi_.size() != n) throw std::invalid_argument("one believed pose per camera is required");
  for (const auto& name : settings_.compare_estimators) {
    RunnerSettings c = settings_;
    c.estimator = name;
    compare_.emplace_back(graph, camera_observer_settings(c, false));
  }
  // Under InitMode::Pnp each camera initialises itself (ObserverSettings::init_from_*).
  const std::vector<bool> paper(n, settings_.init == InitMode::Paper);
  for (auto* o : observers()) {
    o->set_camera_poses(g_wi_);
    o->reset(std::vector<SE3>(n, paper_initial_estimate()));
    o->set_active(paper);
  }
}

std::vector<obs::NetworkedObserver*> Runner::observers() {
  std::vector<obs::NetworkedObserver*> all{&net_, &indep_};
  for (auto& c : compare_) all.push_back(&c);
  return all;
}

void Runner::set_camera_motion(const std::vector<SE3>& g_wi, const std::vector<obs::Vec6>& V_wi) {
  if (g_wi.size() != g_wi_.size() || V_wi.size() != g_wi_.size())
    throw std::invalid_argument("camera motion: one pose and one velocity per camera");
  g_wi_ = g_wi;
  for (auto* o : observers()) {
    o->set_camera_poses(g_wi_);
    o->set_camera_velocities(V_wi);
  }
}

std::optional<SE3> Runner::estimate_world(size_t i) const {
  const auto& c = net_.camera(static_cast<int>(i));
  if (!c.initialized()) return std::nullopt;
  return c.estimate_world();
}

double Runner::step_factor(double dt) const {
  return run::step_factor(net_.settings(), dt, net_.substeps(dt), graph_.max_degree());
}

void evaluate_frame(FrameRecord& r) {
  const size_t n = r.cameras.size();
  std::vector<SE3> pnp_w, fict_w, est(n), ind(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& c = r.cameras[i];
    est[i] = c.est_w;
    if (c.indep_w) ind[i] = *c.indep_w;
    if (c.pnp_w) pnp_w.push_back(*c.pnp_w);
    if (c.fictitious_w) fict_w.push_back(*c.fictitious_w);
  }
  if (!pnp_w.empty()) r.central_w = obs::average_pose(pnp_w);
  if (!fict_w.empty()) {
    r.g_star = obs::average_pose(fict_w);  // (eq:g_ave) over V_f(t)
    std::vector<SE3> net_ready, ind_ready;
    for (size_t i = 0; i < n; ++i) {
      if (r.cameras[i].initialized) net_ready.push_back(est[i]);
      if (r.cameras[i].indep_w) ind_ready.push_back(ind[i]);
    }
    if (net_ready.size() == n) {
      r.energies = obs::energies(net_ready, *r.g_star);
      r.eps = obs::eps_levels(net_ready, *r.g_star, obs::spread(fict_w, *r.g_star),
                              static_cast<int>(fict_w.size()));
    }
    if (!ind_ready.empty()) r.energies_indep = obs::energies(ind_ready, *r.g_star);
    const size_t nc = n ? r.cameras[0].compare_w.size() : 0;
    r.energies_compare.assign(nc, std::nullopt);
    for (size_t e = 0; e < nc; ++e) {
      std::vector<SE3> ready;
      for (const auto& c : r.cameras)
        if (c.compare_w[e]) ready.push_back(*c.compare_w[e]);
      if (ready.size() == n) r.energies_compare[e] = obs::energies(ready, *r.g_star);
    }
  }
}

const FrameRecord& Runner::process(int frame, double t, double dt,
                                   const std::vector<obs::Measurement>& in,
                                   const std::optional<SE3>& g_wo_true) {
  advance(dt, in);
  return record(frame, t, in, g_wo_true);
}

void Runner::advance(double dt, const std::vector<obs::Measurement>& in) {
  const auto n = static_cast<size_t>(graph_.size());
  if (in.size() != n) throw std::invalid_argument("one input per camera is required");
  const auto& model = net_.camera(0).error_model();
  if (model.input() == obs::MeasurementInput::true_pose)
    for (const auto& c : in)
      if (c.delta && !c.g_io_true)
        throw std::invalid_argument("the " + std::string(model.name()) +
                                    " error model needs ground truth (rendered data)");
  for (auto* o : observers()) o->step(dt, in);
}

const FrameRecord& Runner::record(int frame, double t, const std::vector<obs::Measurement>& in,
                                  const std::optional<SE3>& g_wo_true) {
  const auto n = static_cast<size_t>(graph_.size());
  if (in.size() != n) throw std::invalid_argument("one input per camera is required");
  FrameRecord r;
  r.frame = frame;
  r.t = t;
  r.g_wo_true = g_wo_true;
  const auto est = net_.estimates_world();
  const auto ind = indep_.estimates_world();
  r.cameras.resize(n);
  for (size_t i = 0; i < n; ++i) {
    auto& c = r.cameras[i];
    c.delta = in[i].delta;
    c.initialized = net_.camera(static_cast<int>(i)).initialized();
    c.est_w = est[i];
    if (indep_.camera(static_cast<int>(i)).initialized()) c.indep_w = ind[i];
    for (const auto& o : compare_)
      c.compare_w.push_back(o.camera(static_cast<int>(i)).initialized()
                                ? std::optional<SE3>(o.camera(static_cast<int>(i)).estimate_world())
                                : std::nullopt);
    if (in[i].delta && in[i].g_io_pnp) c.pnp_w = g_wi_[i] * *in[i].g_io_pnp;
    if (in[i].delta && in[i].g_io_true)
      c.fictitious_w = g_wi_[i] * *in[i].g_io_true;  // g_wo_i = g_wi g_io_i
  }
  evaluate_frame(r);
  if (!settings_.keep_history) history_.clear();
  history_.push_back(std::move(r));
  return history_.back();
}

}  // namespace netvmo::run
