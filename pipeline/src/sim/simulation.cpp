#include "netvmo/pipeline/sim/simulation.hpp"

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"

namespace netvmo::sim {
namespace fs = std::filesystem;
using obs::Vec3;

std::string simulation_error_model_problem(const std::string& name) {
  const obs::ErrorModel* model = nullptr;
  try {
    model = &obs::error_models().find(name);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  if (model->input() == obs::MeasurementInput::pnp_pose)
    return "the '" + name +
           "' error model needs a measured pose from images; a simulation gives true poses and "
           "projected features (use an error model that reads those)";
  return "";
}

namespace {

SE3 read_pose(io::MapReader m, const char* p_key, const char* r_key) {
  const SE3 g = obs::make_pose(m.get(p_key).vec<3>(), m.get(r_key).vec<3>());
  m.finish();
  return g;
}

obs::ObserverSettings observer_settings(const SimScenario& s) {
  obs::ObserverSettings o;
  o.k_e = s.k_e;
  o.k_s = s.k_s;
  o.error_model = s.error_model;
  o.estimator = s.estimator;
  o.features = obs::FeatureModel::square(s.square_side);
  return o;
}

}  // namespace

SimScenario load_scenario(const fs::path& file) {
  auto root = io::MapReader::from_file(file);
  SimScenario s;
  s.name = root.get_or("name", file.stem().string());
  s.fps = root.get_or("fps", s.fps);
  if (!(s.fps > 0)) root.get("fps").fail("must be positive");
  s.duration = root.get_or("duration", s.duration);
  if (!(s.duration > 0)) root.get("duration").fail("must be positive");
  if (auto gains = root.find("gains")) {
    auto g = gains->map();
    s.k_e = g.get_or("k_e", s.k_e);
    s.k_s = g.get_or("k_s", s.k_s);
    if (!(s.k_e > 0)) g.get("k_e").fail("must be positive");
    if (!(s.k_s >= 0)) g.get("k_s").fail("must be non-negative");
    g.finish();
  }
  s.error_model = root.get_or("error", s.error_model);
  s.estimator = root.get_or("estimator", s.estimator);
  try {
    obs::estimators().find(s.estimator);
  } catch (const std::invalid_argument& e) {
    root.get("estimator").fail(e.what());
  }
  const std::string problem = simulation_error_model_problem(s.error_model);
  if (!problem.empty()) root.get("error").fail(problem);
  s.square_side = root.get_or("square_side", s.square_side);
  if (!(s.square_side > 0)) root.get("square_side").fail("must be positive");
  s.initial = read_pose(root.get("initial_estimate").map(), "p", "r");

  std::set<int> ids;
  std::map<int, int> index_of;
  for (const auto& cv : root.get("cameras").sequence()) {
    auto c = cv.map();
    SimCamera cam;
    cam.id = io::read_camera_id(c.get("id"), ids);
    cam.g_wi = obs::make_pose(c.get("p_wi").vec<3>(), c.get("r_wi").vec<3>());
    if (auto t = c.find("target")) cam.g_wo = read_pose(t->map(), "p", "r");
    c.finish();
    index_of[cam.id] = static_cast<int>(s.cameras.size());
    s.cameras.push_back(cam);
  }
  if (s.cameras.empty()) root.get("cameras").fail("no cameras");
  for (const auto& [i, j] : io::read_edges(root.get("edges"), ids))
    s.edges.emplace_back(index_of[i], index_of[j]);
  root.finish();

  std::vector<int> labels;
  for (const auto& c : s.cameras) labels.push_back(c.id);
  try {
    const obs::Graph g(static_cast<int>(s.cameras.size()), s.edges);
    if (!g.connected())
      throw InputError(file.string() + ": edges: the communication graph is disconnected " +
                       "(Assumption 1); components " +
                       obs::describe_components(g.components(), labels) +
                       ": add an edge joining them");
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string() + ": edges: " + e.what());
  }
  int visible = 0;
  for (const auto& c : s.cameras) visible += c.g_wo.has_value();
  if (visible == 0) throw InputError(file.string() + ": cameras: no camera has a target");
  if (obs::error_models().find(s.error_model).input() == obs::MeasurementInput::features) {
    const auto features = obs::FeatureModel::square(s.square_side);
    for (const auto& c : s.cameras) {
      try {
        obs::project(s.initial, features);
        if (c.g_wo) obs::project(c.g_wi.inverse() * *c.g_wo, features);
      } catch (const std::domain_error&) {
        throw InputError(file.string() + ": camera " + std::to_string(c.id) +
                         ": the target or the initial estimate is behind the camera, so image "
                         "features are undefined for 'error: " +
                         s.error_model +
                         "' (turn the cameras to "
                         "face it, as datasets/paper5_jacobian.yaml does)");
      }
    }
  }
  return s;
}

SimResult simulate(const SimScenario& s) {
  const int n = static_cast<int>(s.cameras.size());
  const obs::Graph graph(n, s.edges);
  const auto settings = observer_settings(s);
  obs::NetworkedObserver observer(graph, settings);

  std::vector<SE3> g_wi, targets;
  std::vector<obs::Measurement> z(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const auto& c = s.cameras[static_cast<size_t>(i)];
    g_wi.push_back(c.g_wi);
    if (!c.g_wo) continue;
    auto& zi = z[static_cast<size_t>(i)];
    zi.delta = true;
    zi.g_io_true = c.g_wi.inverse() * *c.g_wo;  // g_io_i = g_wi^-1 g_wo_i
    if (observer.camera(i).error_model().input() == obs::MeasurementInput::features)
      zi.f = obs::project(*zi.g_io_true, settings.features);
    targets.push_back(*c.g_wo);
  }
  observer.set_camera_poses(g_wi);
  observer.reset(std::vector<SE3>(static_cast<size_t>(n), s.initial));

  SimResult r;
  r.g_star = obs::average_pose(targets);  // (eq:g_ave) over V_f
  r.spread = obs::spread(targets, r.g_star);
  r.W = obs::paper_W(graph);
  r.diameter = graph.diameter();
  const double dt = 1.0 / s.fps;
  r.substeps = observer.substeps(dt);
  const int frames = static_cast<int>(std::lround(s.duration * s.fps));
  const int tail_start = frames - frames / 4;
  const int nv = static_cast<int>(targets.size());
  for (int k = 0; k <= frames; ++k) {
    if (k > 0) observer.step(dt, z);
    const auto est = observer.estimates_world();
    r.t.push_back(k * dt);
    r.energies.push_back(obs::energies(est, r.g_star));
    r.estimates_world.push_back(est);
    const auto lv = obs::eps_levels(est, r.g_star, r.spread, nv);
    if (k >= tail_start) {
      r.eps_tail.eps_p = std::max(r.eps_tail.eps_p, lv.eps_p);
      r.eps_tail.eps_R = std::max(r.eps_tail.eps_R, lv.eps_R);
    }
    if (k == frames) r.eps_final = lv;
  }
  return r;
}

void write_outputs(const SimScenario& s, const SimResult& r, const fs::path& dir) {
  io::ensure_directory(dir);
  {
    io::AtomicFile f(dir / "energies.csv");
    f << "t,U_p,U_R\n";
    for (size_t k = 0; k < r.t.size(); ++k)
      f << r.t[k] << ',' << r.energies[k].U_p << ',' << r.energies[k].U_R << '\n';
    f.commit();
  }
  {
    io::AtomicFile est(dir / "estimates.csv");
    // First element of xi_bar sin(theta_bar) of each world-frame estimate (the paper's Fig. 6),
    // one column per camera.
    io::AtomicFile ori(dir / "orientation_x.csv");
    est << io::kSimulationEstimatesHeader << '\n';
    ori << 't';
    for (const auto& c : s.cameras) ori << ",camera " << c.id;
    ori << '\n';
    for (size_t k = 0; k < r.t.size(); ++k) {
      ori << r.t[k];
      for (size_t i = 0; i < s.cameras.size(); ++i) {
        const SE3& g = r.estimates_world[k][i];
        const Vec3 p = g.translation(), rv = obs::rotvec(g);
        est << r.t[k] << ',' << s.cameras[i].id << ',' << p.x() << ',' << p.y() << ',' << p.z()
            << ',' << rv.x() << ',' << rv.y() << ',' << rv.z() << '\n';
        ori << ',' << obs::e_R(g.linear()).x();
      }
      ori << '\n';
    }
    est.commit();
    ori.commit();
  }
  const auto vec = [](const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  nlohmann::json j;
  j["scenario"] = s.name;
  j["error"] = s.error_model;
  j["estimator"] = s.estimator;
  j["k_e"] = s.k_e;
  j["k_s"] = s.k_s;
  j["fps"] = s.fps;
  j["duration"] = s.duration;
  j["substeps"] = r.substeps;
  j["p_star"] = vec(r.g_star.translation());
  j["xitheta_star"] = vec(obs::rotvec(r.g_star));
  j["xi_sin_theta_star"] = vec(obs::e_R(r.g_star.linear()));
  j["U_p_final"] = r.energies.back().U_p;
  j["U_R_final"] = r.energies.back().U_R;
  j["eps_p"] = r.eps_final.eps_p;
  j["eps_R"] = r.eps_final.eps_R;
  j["eps_p_last_quarter"] = r.eps_tail.eps_p;
  j["eps_R_last_quarter"] = r.eps_tail.eps_R;
  j["rho_p"] = r.spread.rho_p;
  j["rho_R"] = r.spread.rho_R;
  j["phi_m"] = r.spread.phi_m;
  j["theorem1_orientation_offset"] = obs::theorem1_orientation_offset(r.spread);
  j["W"] = r.W.value;
  j["W_exact"] = r.W.exact;
  j["diameter"] = r.diameter;
  nlohmann::json cams = nlohmann::json::array();
  for (size_t i = 0; i < s.cameras.size(); ++i) {
    const SE3& g = r.estimates_world.back()[i];
    cams.push_back(
        {{"id", s.cameras[i].id},
         {"sees_target", s.cameras[i].g_wo.has_value()},
         {"p_final", vec(g.translation())},
         {"xitheta_final", vec(obs::rotvec(g))},
         {"position_error", (g.translation() - r.g_star.translation()).norm()},
         {"orientation_error_deg",
          obs::log_so3(r.g_star.linear().transpose() * g.linear()).norm() * 180.0 / M_PI}});
  }
  j["cameras"] = cams;
  io::write_file_atomic(dir / "summary.json", j.dump(2) + "\n");
}

}  // namespace netvmo::sim
