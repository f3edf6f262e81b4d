#include "netvmo/observer/networked_observer.hpp"

#include <stdexcept>
#include <string>

namespace netvmo::obs {

NetworkedObserver::NetworkedObserver(Graph graph, ObserverSettings settings)
    : graph_(std::move(graph)), settings_(std::move(settings)) {
  if (!graph_.connected())
    throw std::invalid_argument("communication graph is disconnected (Assumption 1); components: " +
                                describe_components(graph_.components(), {}));
  cameras_.reserve(static_cast<size_t>(graph_.size()));
  for (int i = 0; i < graph_.size(); ++i)
    cameras_.emplace_back(i, graph_.neighbors(i), settings_, graph_.size());
  transport_ = std::make_unique<InProcessTransport>(graph_);
}

void NetworkedObserver::check_count(size_t count, const char* what) const {
  if (count != cameras_.size())
    throw std::invalid_argument(std::string(what) + ": wrong count (" + std::to_string(count) +
                                " for " + std::to_string(cameras_.size()) + " cameras)");
}

void NetworkedObserver::reset(const std::vector<SE3>& g_bar) {
  check_count(g_bar.size(), "reset");
  for (size_t i = 0; i < cameras_.size(); ++i) cameras_[i].reset(g_bar[i]);
}

void NetworkedObserver::set_camera_poses(const std::vector<SE3>& g_wi) {
  check_count(g_wi.size(), "camera poses");
  for (size_t i = 0; i < cameras_.size(); ++i) cameras_[i].set_camera_pose(g_wi[i]);
}

void NetworkedObserver::set_camera_velocities(const std::vector<Vec6>& V_wi) {
  check_count(V_wi.size(), "camera velocities");
  for (size_t i = 0; i < cameras_.size(); ++i) cameras_[i].set_camera_velocity(V_wi[i]);
}

void NetworkedObserver::set_active(const std::vector<bool>& active) {
  check_count(active.size(), "active mask");
  for (size_t i = 0; i < cameras_.size(); ++i) cameras_[i].set_initialized(active[i]);
}

std::vector<bool> NetworkedObserver::active() const {
  std::vector<bool> a;
  for (const auto& c : cameras_) a.push_back(c.initialized());
  return a;
}

void NetworkedObserver::set_transport(std::unique_ptr<Transport> transport) {
  if (!transport) throw std::invalid_argument("set_transport: no transport");
  transport_ = std::move(transport);
}

int NetworkedObserver::substeps(double dt) const {
  return frame_substeps(dt, settings_, graph_.max_degree());
}

void NetworkedObserver::step(double dt, const std::vector<Measurement>& z) {
  check_count(z.size(), "step: measurements");
  for (size_t i = 0; i < cameras_.size(); ++i) cameras_[i].set_measurement(z[i]);
  const int N = substeps(dt);
  const double h = dt / N;
  for (int k = 0; k < N; ++k) {
    // One exchange round: every camera publishes g_wi g_bar_i, then every camera takes in its
    // neighbours' messages and steps (all on the estimates of the previous sub-step).
    for (auto& c : cameras_) transport_->send(c.publish());
    for (auto& c : cameras_) {
      transport_->receive(c.index(), inbox_);
      for (const auto& m : inbox_) c.receive(m);
    }
    for (auto& c : cameras_) c.step(h);  // (eq:EsRRBM) with (eq:input_f-)
  }
}

std::vector<SE3> NetworkedObserver::estimates() const {
  std::vector<SE3> out;
  out.reserve(cameras_.size());
  for (const auto& c : cameras_) out.push_back(c.estimate());
  return out;
}

std::vector<SE3> NetworkedObserver::estimates_world() const {
  std::vector<SE3> out;
  out.reserve(cameras_.size());
  for (const auto& c : cameras_) out.push_back(c.estimate_world());
  return out;
}

std::vector<Vec6> NetworkedObserver::inputs() const {
  std::vector<Vec6> out;
  out.reserve(cameras_.size());
  for (const auto& c : cameras_) out.push_back(c.input());
  return out;
}

}  // namespace netvmo::obs
