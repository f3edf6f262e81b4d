#include "netvmo/observer/networked_observer.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <thread>

#include "in_process_vmo.hpp"
#include "netvmo/observer/exchange.hpp"

namespace netvmo::obs {

NetworkedObserver::NetworkedObserver(Graph graph, ObserverSettings settings)
    : graph_(std::move(graph)), settings_(std::move(settings)) {
  if (!graph_.connected())
    throw std::invalid_argument("communication graph is disconnected (Assumption 1); components: " +
                                describe_components(graph_.components(), {}));
  if (settings_.threads < 0)
    throw std::invalid_argument("threads must be >= 0 (0: one per core), not " +
                                std::to_string(settings_.threads));
  cameras_.reserve(static_cast<size_t>(graph_.size()));
  for (int i = 0; i < graph_.size(); ++i)
    cameras_.emplace_back(i, graph_.neighbors(i), settings_, graph_.size());
  transport_ = std::make_unique<InProcessTransport>(graph_);
  const int cores = settings_.threads > 0
                        ? settings_.threads
                        : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int threads = std::min(cores, std::max(1, graph_.size() / kCamerasPerThread));
  if (threads > 1) pool_ = std::make_unique<WorkerPool>(threads);
  if (!cameras_.empty() && InProcessVmo::supports(cameras_.front()))
    fast_ = std::make_unique<InProcessVmo>(graph_);
}

NetworkedObserver::~NetworkedObserver() = default;
NetworkedObserver::NetworkedObserver(NetworkedObserver&&) noexcept = default;
NetworkedObserver& NetworkedObserver::operator=(NetworkedObserver&&) noexcept = default;

int NetworkedObserver::threads() const {
  return pool_ ? pool_->size() : 1;
}

void NetworkedObserver::for_each_camera(const std::function<void(int)>& f) {
  const int n = size();
  if (pool_)
    pool_->for_each(n, pool_->size(), f);
  else
    for (int i = 0; i < n; ++i) f(i);
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
  // Direct delivery over the same graph is what the in-process fast path does too.
  direct_ = false;
  if (const auto* direct = dynamic_cast<const InProcessTransport*>(transport.get())) {
    direct_ = direct->graph().size() == graph_.size();
    for (int i = 0; direct_ && i < graph_.size(); ++i)
      direct_ = direct->graph().neighbors(i) == graph_.neighbors(i);
  }
  transport_ = std::move(transport);
  stored_known_ = false;
}

int NetworkedObserver::substeps(double dt) const {
  return frame_substeps(dt, settings_, graph_.max_degree());
}

void NetworkedObserver::step(double dt, const std::vector<Measurement>& z) {
  check_count(z.size(), "step: measurements");
  const int N = substeps(dt);
  const double h = dt / N;
  int k = 0;
  if (!direct_ || !fast_)
    for_each_camera([&](int i) {
      cameras_[static_cast<size_t>(i)].set_measurement(z[static_cast<size_t>(i)]);
    });
  else {  // (the fast path sets the measurements in its first pass)
    // The same rounds on compact arrays; it hands over to exchange rounds when a message would be
    // refused (then the rest of the frame is exchanged camera by camera).
    const bool known = stored_known_;
    stored_known_ = false;  // until the frame is done (a throw leaves it false)
    k = fast_->run(cameras_, z, N, h, pool_.get(), !known);
    stored_known_ = k == N;
  }
  for (; k < N; ++k) exchange_round(h);
}

void NetworkedObserver::exchange_round(double h) {
  // exchange.hpp: every camera sends, then every camera takes in what reached it (the transport
  // is called from this thread only), then every camera steps on the estimates of the previous
  // sub-step, on the pool's threads.
  for (auto& c : cameras_) send_estimate(c, *transport_);
  for (auto& c : cameras_) take_estimates(c, *transport_, inbox_);
  // (eq:EsRRBM) with (eq:input_f-)
  for_each_camera([&](int i) { cameras_[static_cast<size_t>(i)].step(h); });
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
