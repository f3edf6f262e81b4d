#include "netvmo/observer/camera_observer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "in_process_vmo.hpp"
#include "pose_kernel.hpp"

namespace netvmo::obs {

Vec6 mutual_error(const SE3& g_bar_w_i, const SE3& g_bar_w_j) {
  return kernel::mutual_error(kernel::pose_of(g_bar_w_i), kernel::pose_of(g_bar_w_j));
}

Vec6 mutual_sum(const SE3& g_bar_w_i, const std::vector<SE3>& g_bar_w_nb) {
  kernel::PoseSum nb;
  for (const auto& g : g_bar_w_nb) nb.add(kernel::pose_of(g));
  return kernel::mutual_sum(kernel::pose_of(g_bar_w_i), nb);
}

SE3 integrate(const SE3& g_bar, const Vec6& V_wi, const Vec6& u, double h) {
  return kernel::to_se3(kernel::integrate(kernel::pose_of(g_bar), V_wi, u, h));
}

CameraObserver::CameraObserver(int index, std::vector<int> neighbours, ObserverSettings settings,
                               int network_size)
    : index_(index),
      neighbours_(std::move(neighbours)),
      settings_(std::move(settings)),
      model_(&error_models().find(settings_.error_model)),
      estimator_(&estimators().find(settings_.estimator)),
      network_size_(network_size) {
  if (!(settings_.k_e >= 0.0) || !(settings_.k_s >= 0.0))
    throw std::invalid_argument("gains k_e and k_s must be non-negative");
  if (!(settings_.step_factor > 0.0 && settings_.step_factor < 2.0))
    throw std::invalid_argument("step_factor must lie in (0, 2)");
  for (size_t a = 0; a < neighbours_.size(); ++a) {
    if (neighbours_[a] == index_)
      throw std::invalid_argument("camera " + std::to_string(index_) +
                                  " lists itself as a neighbour");
    if (std::count(neighbours_.begin(), neighbours_.end(), neighbours_[a]) > 1)
      throw std::invalid_argument("camera " + std::to_string(index_) + " lists neighbour " +
                                  std::to_string(neighbours_[a]) + " twice");
  }
  estimator_->check(settings_, *model_, network_size_);
  latest_.get().resize(neighbours_.size());
  refused_.assign(5, 0);
}

EstimateMessage CameraObserver::publish(double stamp) {
  EstimateMessage m;
  publish(m, stamp);
  return m;
}

void CameraObserver::publish(EstimateMessage& m, double stamp) {
  m.sender = index_;
  m.round = ++round_;
  m.stamp = stamp;
  m.initialized = st_.initialized;
  m.incarnation = incarnation_;
  m.g_w = g_wi_ * st_.g_bar;
  const auto k = static_cast<size_t>(estimator_->state_size());
  std::copy(st_.consensus.begin(), st_.consensus.begin() + k, m.state.begin());
}

MessageVerdict CameraObserver::receive(const EstimateMessage& m) {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), m.sender);
  MessageVerdict v = it == neighbours_.end() ? MessageVerdict::not_a_neighbour : check_pose(m.g_w);
  if (v == MessageVerdict::accepted &&
      !Eigen::Map<const Eigen::Matrix<double, kConsensusStateSize, 1>>(m.state.data()).allFinite())
    v = MessageVerdict::not_finite;
  auto* slot = v == MessageVerdict::accepted
                   ? &latest_.get()[static_cast<size_t>(it - neighbours_.begin())]
                   : nullptr;
  if (slot && *slot &&
      (m.incarnation < (*slot)->incarnation ||
       (m.incarnation == (*slot)->incarnation && m.round <= (*slot)->round)))
    v = MessageVerdict::out_of_order;
  if (v != MessageVerdict::accepted) {
    ++refused_[static_cast<size_t>(v)];
    return v;
  }
  // Stored field by field, the consensus state only as far as the estimator reads it (the
  // rest of the stored state stays zero): the paper's observer copies no consensus state.
  auto& kept = slot->has_value() ? **slot : slot->emplace();
  kept.sender = m.sender;
  kept.round = m.round;
  kept.stamp = m.stamp;
  kept.initialized = m.initialized;
  kept.incarnation = m.incarnation;
  kept.g_w = m.g_w;
  std::copy(m.state.begin(), m.state.begin() + estimator_->state_size(), kept.state.begin());
  return v;
}

void CameraObserver::forget(int j) {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), j);
  if (it != neighbours_.end()) latest_.get()[static_cast<size_t>(it - neighbours_.begin())].reset();
}

void CameraObserver::set_measurement(const Measurement& z) {
  z_ = z;
  estimator_->measured({settings_, *model_, z_}, st_);
}

void CameraObserver::step(double h) {
  estimator_->step(context(), st_, h);
  // The camera moves on with its body velocity over the sub-step, d/dt g_wi = g_wi hat(V_wi):
  // the next message g_wi g_bar_i pairs the estimate with the pose it now refers to.
  if (!V_wi_.isZero(0.0)) {
    g_wi_ = g_wi_ * exp_se3(h * V_wi_);
    g_wi_.linear() = Eigen::Quaterniond(g_wi_.linear()).normalized().toRotationMatrix();
  }
}

CameraObserver::NeighbourMessages& CameraObserver::NeighbourMessages::operator=(
    const NeighbourMessages& o) {
  if (this != &o) {
    slots_ = o.get();
    state_.store(kWritten, std::memory_order_release);
  }
  return *this;
}

CameraObserver::NeighbourMessages& CameraObserver::NeighbourMessages::operator=(
    NeighbourMessages&& o) noexcept {
  if (this != &o) {
    slots_ = std::move(o.get());
    state_.store(kWritten, std::memory_order_release);
  }
  return *this;
}

void CameraObserver::NeighbourMessages::defer(const InProcessVmo* source, int position) {
  source_ = source;
  position_ = position;
  state_.store(kDeferred, std::memory_order_release);
}

void CameraObserver::NeighbourMessages::write() const {
  // One reader writes the slots; any other waits until they are written.
  int expected = kDeferred;
  if (state_.compare_exchange_strong(expected, kWriting, std::memory_order_acquire)) {
    source_->fill(position_, slots_);
    state_.store(kWritten, std::memory_order_release);
    return;
  }
  while (state_.load(std::memory_order_acquire) != kWritten) std::this_thread::yield();
}

}  // namespace netvmo::obs
