#include "netvmo/pipeline/run/runner.hpp"

#include <stdexcept>

#include "netvmo/observer/jacobian.hpp"

namespace netvmo::run {

InitMode parse_init_mode(const std::string& s) {
  if (s == "pnp") return InitMode::Pnp;
  if (s == "paper") return InitMode::Paper;
  throw std::invalid_argument("unknown initialisation '" + s + "' (pnp or paper)");
}

const char* to_string(InitMode m) { return m == InitMode::Pnp ? "pnp" : "paper"; }

SE3 paper_initial_estimate() {
  SE3 g = SE3::Identity();
  g.translation() = obs::Vec3(0, 0, 1);
  g.linear() = obs::Vec3(1, -1, -1).asDiagonal();
  return g;
}

namespace {
obs::ObserverSettings observer_settings(const RunnerSettings& s, double k_s) {
  obs::ObserverSettings o;
  o.k_e = s.k_e;
  o.k_s = k_s;
  o.error_model = s.error_model;
  o.features = obs::FeatureModel::square(s.tag_size);
  o.substeps = s.rounds;
  return o;
}

// Smallest depth of the tag corners under an estimate (camera frame).
double min_depth(const SE3& g_bar, const obs::FeatureModel& m) {
  double z = 1e300;
  for (const auto& p : m.points_o) z = std::min(z, (g_bar * p).z());
  return z;
}
}  // namespace

NetworkRunner::NetworkRunner(const obs::Graph& graph, std::vector<SE3> g_wi,
                             RunnerSettings settings)
    : graph_(graph),
      g_wi_(std::move(g_wi)),
      settings_(settings),
      net_(graph, observer_settings(settings, settings.k_s)),
      indep_(graph, observer_settings(settings, 0.0)) {
  const auto n = static_cast<size_t>(graph_.size());
  if (g_wi_.size() != n) throw std::invalid_argument("one believed pose per camera is required");
  net_.set_camera_poses(g_wi_);
  indep_.set_camera_poses(g_wi_);
  const bool paper = settings_.init == InitMode::Paper;
  net_init_.assign(n, paper);
  indep_init_.assign(n, paper);
  net_.reset(std::vector<SE3>(n, paper_initial_estimate()));
  indep_.reset(std::vector<SE3>(n, paper_initial_estimate()));
  net_.set_active(net_init_);
  indep_.set_active(indep_init_);
}

void NetworkRunner::set_camera_motion(const std::vector<SE3>& g_wi, const std::vector<obs::Vec6>& V_wi) {
  if (g_wi.size() != g_wi_.size() || V_wi.size() != g_wi_.size())
    throw std::invalid_argument("camera motion: one pose and one velocity per camera");
  g_wi_ = g_wi;
  for (auto* o : {&net_, &indep_}) {
    o->set_camera_poses(g_wi_);
    o->set_camera_velocities(V_wi);
  }
}

double NetworkRunner::step_factor(double dt) const {
  const double h = dt / net_.substeps(dt);
  return h * (settings_.k_e + 2.0 * settings_.k_s * graph_.max_degree());
}

void NetworkRunner::initialise(const std::vector<CameraInput>& in) {
  const int n = graph_.size();
  std::vector<SE3> net = net_.estimates(), ind = indep_.estimates();
  const auto features = obs::FeatureModel::square(settings_.tag_size);
  // An estimate of the image-feature model must keep the tag in front of the camera.
  const bool features_model = net_.camera(0).error_model().input() == obs::MeasurementInput::features;
  bool net_changed = false, ind_changed = false;
  // 1. Cameras that see the target start from (or are rescued by) their own PnP pose.
  for (int i = 0; i < n; ++i) {
    const auto si = static_cast<size_t>(i);
    const auto& c = in[si];
    if (!c.delta || !c.g_io_pnp) continue;
    const bool net_unusable = features_model && net_init_[si] &&
                              min_depth(net[si], features) < settings_.min_feature_depth;
    if (!net_init_[si] || net_unusable) {
      net[si] = *c.g_io_pnp;
      net_init_[si] = true;
      net_changed = true;
    }
    const bool ind_unusable = features_model && indep_init_[si] &&
                              min_depth(ind[si], features) < settings_.min_feature_depth;
    if (!indep_init_[si] || ind_unusable) {
      ind[si] = *c.g_io_pnp;
      indep_init_[si] = true;
      ind_changed = true;
    }
  }
  // 2. Blind cameras start from the average of their initialised neighbours' estimates,
  //    mapped into their own frame: g_bar_i = g_wi^-1 avg_j(g_wj g_bar_j). Repeated so that
  //    initialisation spreads across the graph within one frame.
  for (bool progress = true; progress;) {
    progress = false;
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<size_t>(i);
      if (net_init_[si]) continue;
      std::vector<SE3> nb;
      for (int j : graph_.neighbors(i))
        if (net_init_[static_cast<size_t>(j)]) nb.push_back(g_wi_[static_cast<size_t>(j)] * net[static_cast<size_t>(j)]);
      if (nb.empty()) continue;
      net[si] = g_wi_[si].inverse() * obs::average_pose(nb);
      net_init_[si] = true;
      progress = net_changed = true;
    }
  }
  if (net_changed) {
    net_.reset(net);
    net_.set_active(net_init_);
  }
  if (ind_changed) {
    indep_.reset(ind);
    indep_.set_active(indep_init_);
  }
}

const FrameRecord& NetworkRunner::process(int frame, double t, double dt,
                                          const std::vector<CameraInput>& in,
                                          const std::optional<SE3>& g_wo_true) {
  const auto n = static_cast<size_t>(graph_.size());
  if (in.size() != n) throw std::invalid_argument("one input per camera is required");
  if (settings_.init == InitMode::Pnp) initialise(in);

  const auto& model = net_.camera(0).error_model();
  if (model.input() == obs::MeasurementInput::true_pose)
    for (const auto& c : in)
      if (c.delta && !c.g_io_true)
        throw std::invalid_argument("the " + std::string(model.name()) +
                                    " error model needs ground truth (rendered data)");
  net_.step(dt, in);
  indep_.step(dt, in);

  FrameRecord r;
  r.frame = frame;
  r.t = t;
  r.g_wo_true = g_wo_true;
  const auto est = net_.estimates_world();
  const auto ind = indep_.estimates_world();
  std::vector<SE3> pnp_w, fict_w;
  r.cameras.resize(n);
  for (size_t i = 0; i < n; ++i) {
    auto& c = r.cameras[i];
    c.delta = in[i].delta;
    c.initialized = net_init_[i];
    c.est_w = est[i];
    if (indep_init_[i]) c.indep_w = ind[i];
    if (in[i].delta && in[i].g_io_pnp) {
      c.pnp_w = g_wi_[i] * *in[i].g_io_pnp;
      pnp_w.push_back(*c.pnp_w);
    }
    if (in[i].delta && in[i].g_io_true) {
      c.fictitious_w = g_wi_[i] * *in[i].g_io_true;  // g_wo_i = g_wi g_io_i
      fict_w.push_back(*c.fictitious_w);
    }
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
  }
  history_.push_back(std::move(r));
  return history_.back();
}

}  // namespace netvmo::run
