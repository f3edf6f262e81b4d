#include "netvmo/observer/camera_observer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "netvmo/observer/metrics.hpp"

namespace netvmo::obs {

const char* to_string(MessageVerdict v) {
  switch (v) {
    case MessageVerdict::accepted:
      return "accepted";
    case MessageVerdict::not_a_neighbour:
      return "not a neighbour";
    case MessageVerdict::not_finite:
      return "pose not finite";
    case MessageVerdict::not_a_rotation:
      return "rotation not orthonormal";
    case MessageVerdict::out_of_order:
      return "out of order";
  }
  return "?";
}

Vec6 mutual_error(const SE3& g_bar_w_i, const SE3& g_bar_w_j) {
  // E_R(A^-1 B) = [R_A^T (p_B - p_A); e_R(R_A^T R_B)] without forming the product.
  const Mat3 Rt = g_bar_w_i.linear().transpose();
  Vec6 e;
  e.head<3>() = Rt * (g_bar_w_j.translation() - g_bar_w_i.translation());
  e.tail<3>() = e_R(Rt * g_bar_w_j.linear());
  return e;
}

SE3 integrate(const SE3& g_bar, const Vec6& V_wi, const Vec6& u, double h) {
  SE3 g = g_bar * exp_se3(h * u);
  if (!V_wi.isZero(0.0)) g = exp_se3(-h * V_wi) * g;
  // Re-orthonormalise against round-off drift over long runs (cheap: unit quaternion).
  g.linear() = Eigen::Quaterniond(g.linear()).normalized().toRotationMatrix();
  return g;
}

int frame_substeps(double dt, const ObserverSettings& s, int max_degree) {
  return s.substeps > 0 ? s.substeps : stable_substeps(dt, s, max_degree);
}

int stable_substeps(double dt, const ObserverSettings& s, int max_degree) {
  const double lambda_max = s.k_e + 2.0 * s.k_s * max_degree;
  return std::max(1, static_cast<int>(std::ceil(dt * lambda_max / s.step_factor - 1e-12)));
}

CameraObserver::CameraObserver(int index, std::vector<int> neighbours, ObserverSettings settings)
    : index_(index),
      neighbours_(std::move(neighbours)),
      settings_(std::move(settings)),
      model_(&find_error_model(settings_.error_model)) {
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
  latest_.resize(neighbours_.size());
  refused_.assign(5, 0);
}

EstimateMessage CameraObserver::publish(double stamp) {
  EstimateMessage m;
  m.sender = index_;
  m.round = ++round_;
  m.stamp = stamp;
  m.initialized = initialized_;
  m.incarnation = incarnation_;
  m.g_w = g_wi_ * g_bar_;
  return m;
}

MessageVerdict check_pose(const SE3& g) {
  if (!g.matrix().allFinite()) return MessageVerdict::not_finite;
  const Mat3 R = g.linear();
  if (!((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-6) ||
      !(R.determinant() > 0.0))
    return MessageVerdict::not_a_rotation;
  return MessageVerdict::accepted;
}

MessageVerdict CameraObserver::receive(const EstimateMessage& m) {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), m.sender);
  MessageVerdict v = it == neighbours_.end() ? MessageVerdict::not_a_neighbour : check_pose(m.g_w);
  auto* slot = v == MessageVerdict::accepted
                   ? &latest_[static_cast<size_t>(it - neighbours_.begin())]
                   : nullptr;
  if (slot && *slot &&
      (m.incarnation < (*slot)->incarnation ||
       (m.incarnation == (*slot)->incarnation && m.round <= (*slot)->round)))
    v = MessageVerdict::out_of_order;
  if (v != MessageVerdict::accepted) {
    ++refused_[static_cast<size_t>(v)];
    return v;
  }
  *slot = m;
  return v;
}

void CameraObserver::forget(int j) {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), j);
  if (it != neighbours_.end()) latest_[static_cast<size_t>(it - neighbours_.begin())].reset();
}

namespace {
// Smallest depth of the target's feature points under an estimate (camera frame).
double min_depth(const SE3& g_bar, const FeatureModel& m) {
  double z = 1e300;
  for (const auto& p : m.points_o) z = std::min(z, (g_bar * p).z());
  return z;
}
}  // namespace

void CameraObserver::set_measurement(const Measurement& z) {
  z_ = z;
  if (!settings_.init_from_measurement || !z.delta || !z.g_io_pnp) return;
  // An estimate of the image-feature model must keep the tag in front of the camera.
  const bool unusable = initialized_ && model_->input() == MeasurementInput::features &&
                        min_depth(g_bar_, settings_.features) < settings_.min_feature_depth;
  if (!initialized_ || unusable) {
    g_bar_ = *z.g_io_pnp;
    initialized_ = true;
  }
}

void CameraObserver::step(double h) {
  if (!initialized_ && settings_.init_from_neighbours) {
    std::vector<SE3> nb;
    for (const auto& m : latest_)
      if (m && m->initialized) nb.push_back(m->g_w);
    if (!nb.empty()) {
      g_bar_ = g_wi_.inverse() * average_pose(nb);
      initialized_ = true;
    }
  }
  if (!initialized_) return;
  const SE3 own_w = g_wi_ * g_bar_;
  Vec6 mutual = Vec6::Zero();
  for (const auto& m : latest_)
    if (m && m->initialized) mutual += mutual_error(own_w, m->g_w);
  Vec6 u = settings_.k_s * mutual;  // (eq:input_f-)
  if (model_->usable(z_)) u += settings_.k_e * model_->error(g_bar_, z_, settings_.features);
  u_ = u;
  g_bar_ = integrate(g_bar_, V_wi_, u_, h);  // (eq:EsRRBM)
}

}  // namespace netvmo::obs
