#include "in_process_vmo.hpp"

#include <algorithm>
#include <atomic>
#include <exception>

namespace netvmo::obs {

InProcessVmo::InProcessVmo(const Graph& graph) : n_(graph.size()) {
  const auto n = static_cast<size_t>(n_);
  offset_.reserve(n + 1);
  offset_.push_back(0);
  for (int i = 0; i < n_; ++i) {
    for (int j : graph.neighbors(i)) nbr_.push_back(j);
    offset_.push_back(static_cast<int>(nbr_.size()));
  }
  g_bar_.resize(n);
  g_wi_.resize(n);
  for (auto& b : pub_) b.resize(n);
  for (auto& b : pub_init_) b.resize(n);
  init_.resize(n);
  moving_.resize(n);
  wi_room_.resize(n);
  sees_.resize(n);
  u_.resize(n);
  round0_.resize(n);
  incarnation_.resize(n);
}

bool InProcessVmo::supports(const CameraObserver& camera) {
  return &camera.estimator() == &estimators().find("vmo");
}

void InProcessVmo::for_each(WorkerPool* pool, const std::function<void(int)>& f) const {
  if (pool)
    pool->for_each(n_, pool->size(), f);
  else
    for (int i = 0; i < n_; ++i) f(i);
}

bool InProcessVmo::gather(const CameraObserver& c, int i) {
  const auto k = static_cast<size_t>(i);
  g_bar_[k] = kernel::pose_of(c.st_.g_bar);
  g_wi_[k] = kernel::pose_of(c.g_wi_);
  wi_room_[k] = kernel::check_has_room(g_wi_[k]);
  moving_[k] = !c.V_wi_.isZero(0.0);
  init_[k] = c.st_.initialized;
  u_[k] = c.st_.u;
  sees_[k] = c.model_->usable(c.z_);
  round0_[k] = c.round_;
  incarnation_[k] = c.incarnation_;
  // The first round's message (CameraObserver::publish).
  pub_[0][k] = kernel::compose(g_wi_[k], g_bar_[k]);
  pub_init_[0][k] = init_[k];
  return kernel::check_pose(pub_[0][k]) == MessageVerdict::accepted;
}

bool InProcessVmo::step(int i, int cur, const Measurement& z, double h, bool publish) {
  const auto k = static_cast<size_t>(i);
  const auto& P = pub_[cur];
  const auto& P_init = pub_init_[cur];
  const int* first = nbr_.data() + offset_[k];
  const int* last = nbr_.data() + offset_[k + 1];
  bool started = false, unit = false;
  if (!init_[k] && s_->init_from_neighbours) {  // Vmo::step's self-initialisation
    std::vector<SE3> nb;
    for (const int* j = first; j != last; ++j)
      if (P_init[static_cast<size_t>(*j)]) nb.push_back(kernel::to_se3(P[static_cast<size_t>(*j)]));
    if (!nb.empty()) {
      g_bar_[k] = kernel::pose_of(kernel::start_from_neighbours(kernel::to_se3(g_wi_[k]), nb));
      init_[k] = 1;
      started = true;
    }
  }
  if (init_[k]) {  // Vmo::step: (eq:EsRRBM) with (eq:input_f-)
    // This camera's own message of the round is g_wi g_bar_i (unless it has just started).
    const kernel::Pose own_w = started ? kernel::compose(g_wi_[k], g_bar_[k]) : P[k];
    kernel::PoseSum nb;
    for (const int* j = first; j != last; ++j)
      if (P_init[static_cast<size_t>(*j)]) nb.add(P[static_cast<size_t>(*j)]);
    const Vec6 mutual = kernel::mutual_sum(own_w, nb);
    Vec6 visual;
    if (sees_[k]) visual = model_->error(kernel::to_se3(g_bar_[k]), z, s_->features);
    u_[k] = kernel::vmo_input(*s_, mutual, sees_[k] ? &visual : nullptr);
    // Static camera (V_wi = 0): frames with a moving camera never reach this loop (run()).
    static const Vec6 still = Vec6::Zero();
    g_bar_[k] = kernel::integrate(g_bar_[k], still, u_[k], h, &unit);
  }
  if (!publish) return true;
  auto& next = pub_[1 - cur][k];
  next = kernel::compose(g_wi_[k], g_bar_[k]);
  pub_init_[1 - cur][k] = init_[k];
  // CameraObserver::receive's check, which accepts every finite product of a camera pose with
  // room and a rotation fresh from the quaternion (kernel::check_has_room).
  if (unit && wi_room_[k]) return kernel::finite(next);
  return kernel::check_pose(next) == MessageVerdict::accepted;
}

void InProcessVmo::write_back(std::vector<CameraObserver>& cams, int i, int done, int cur) const {
  const auto k = static_cast<size_t>(i);
  auto& c = cams[k];
  c.st_.g_bar = kernel::to_se3(g_bar_[k]);
  c.st_.u = u_[k];
  c.st_.initialized = init_[k];
  c.round_ = round0_[k] + static_cast<std::uint64_t>(done);
  // What CameraObserver::receive stored of each neighbour's message of the last round.
  for (int a = offset_[k]; a < offset_[k + 1]; ++a) {
    const auto j = static_cast<size_t>(nbr_[static_cast<size_t>(a)]);
    auto& slot = c.latest_[static_cast<size_t>(a - offset_[k])];
    auto& kept = slot.has_value() ? *slot : slot.emplace();
    kept.sender = static_cast<int>(j);
    kept.round = round0_[j] + static_cast<std::uint64_t>(done);
    kept.stamp = 0.0;
    kept.initialized = pub_init_[cur][j];
    kept.incarnation = incarnation_[j];
    kept.g_w = kernel::to_se3(pub_[cur][j]);
  }
}

int InProcessVmo::run(std::vector<CameraObserver>& cams, const std::vector<Measurement>& z,
                      int rounds, double h, WorkerPool* pool, bool check_stored) {
  s_ = &cams.front().settings();
  model_ = &cams.front().error_model();
  std::atomic<bool> refused{false};
  for_each(pool, [&](int i) {
    auto& c = cams[static_cast<size_t>(i)];
    c.set_measurement(z[static_cast<size_t>(i)]);
    if (!gather(c, i)) refused.store(true, std::memory_order_relaxed);
  });
  if (check_stored)  // CameraObserver::receive's out-of-order test on the first round's messages
    for_each(pool, [&](int i) {
      const auto& latest = cams[static_cast<size_t>(i)].latest_;
      for (int a = offset_[static_cast<size_t>(i)]; a < offset_[static_cast<size_t>(i) + 1]; ++a) {
        const auto j = static_cast<size_t>(nbr_[static_cast<size_t>(a)]);
        const auto& slot = latest[static_cast<size_t>(a - offset_[static_cast<size_t>(i)])];
        if (slot && (incarnation_[j] < slot->incarnation ||
                     (incarnation_[j] == slot->incarnation && round0_[j] + 1 <= slot->round)))
          refused.store(true, std::memory_order_relaxed);
      }
    });
  if (refused) return 0;
  // A moving camera's believed pose moves on over the sub-steps (CameraObserver::step); those
  // frames take the camera-by-camera loop.
  if (std::any_of(moving_.begin(), moving_.end(), [](unsigned char m) { return m != 0; })) return 0;

  int done = 0, cur = 0;
  if (rounds <= 0) {
    for_each(pool, [&](int i) { write_back(cams, i, done, cur); });
    return 0;
  }
  try {
    while (done + 1 < rounds) {
      for_each(pool, [&](int i) {
        if (!step(i, cur, z[static_cast<size_t>(i)], h, true))
          refused.store(true, std::memory_order_relaxed);
      });
      ++done;
      if (refused) {  // the next round runs the per-camera way
        for_each(pool, [&](int i) { write_back(cams, i, done, cur); });
        return done;
      }
      cur = 1 - cur;
    }
    // The last round publishes nothing, so the neighbours' messages it reads (buffer cur) stay
    // as they are while it runs: each camera writes its state back right after its step.
    for_each(pool, [&](int i) {
      step(i, cur, z[static_cast<size_t>(i)], h, false);
      write_back(cams, i, done + 1, cur);
    });
    return ++done;
  } catch (...) {
    const auto error = std::current_exception();
    ++done;
    for_each(pool, [&](int i) { write_back(cams, i, done, cur); });
    std::rethrow_exception(error);
  }
}

}  // namespace netvmo::obs
