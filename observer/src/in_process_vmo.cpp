#include "in_process_vmo.hpp"

#include <algorithm>
#include <atomic>
#include <exception>

namespace netvmo::obs {

namespace {
// The cameras in breadth-first order from a pseudo-peripheral camera (George and Liu's heuristic:
// the camera a breadth-first search from camera 0 reaches last starts a second one). Cameras
// that are neighbours get nearby positions, so each thread's contiguous part of the positions
// (WorkerPool; most of it run by that thread) reads mostly estimates its own part wrote (few cache
// lines cross between cores in a round) and a camera's neighbours share cache lines. (A camera no
// search reaches, in a disconnected graph NetworkedObserver refuses anyway, is appended.)
std::vector<int> breadth_first_order(const Graph& g) {
  const auto n = static_cast<size_t>(g.size());
  const auto search = [&](int start) {
    std::vector<int> order;
    std::vector<unsigned char> seen(n, 0);
    order.reserve(n);
    for (int s = start; order.size() < n;
         s = static_cast<int>(std::find(seen.begin(), seen.end(), 0) - seen.begin())) {
      seen[static_cast<size_t>(s)] = 1;
      order.push_back(s);
      for (size_t head = order.size() - 1; head < order.size(); ++head)
        for (int j : g.neighbors(order[head]))
          if (!seen[static_cast<size_t>(j)]) {
            seen[static_cast<size_t>(j)] = 1;
            order.push_back(j);
          }
    }
    return order;
  };
  if (n == 0) return {};
  return search(search(0).back());
}
}  // namespace

InProcessVmo::InProcessVmo(const Graph& graph)
    : n_(graph.size()), order_(breadth_first_order(graph)) {
  const auto n = static_cast<size_t>(n_);
  position_.resize(n);
  for (size_t p = 0; p < n; ++p) position_[static_cast<size_t>(order_[p])] = static_cast<int>(p);
  // CSR adjacency by position, each camera's neighbours in its own order (the order of the sum
  // of the mutual term, so the arithmetic is the per-camera exchange's).
  offset_.reserve(n + 1);
  offset_.push_back(0);
  for (size_t p = 0; p < n; ++p) {
    for (int j : graph.neighbors(order_[p])) nbr_.push_back(position_[static_cast<size_t>(j)]);
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
  pose_visual_.resize(n);
  g_io_.resize(n);
  u_.resize(n);
  round0_.resize(n);
  incarnation_.resize(n);
  kept_.resize(n);
  kept_init_.resize(n);
  kept_round_.resize(n);
  kept_incarnation_.resize(n);
}

bool InProcessVmo::supports(const CameraObserver& camera) {
  return &camera.estimator() == &estimators().find("vmo");
}

void InProcessVmo::for_each(WorkerPool* pool, int count, const std::function<void(int)>& f) const {
  if (pool)
    pool->for_each(count, pool->size(), f);
  else
    for (int i = 0; i < count; ++i) f(i);
}

bool InProcessVmo::gather(const CameraObserver& c, int p) {
  const auto k = static_cast<size_t>(p);
  g_bar_[k] = kernel::pose_of(c.st_.g_bar);
  g_wi_[k] = kernel::pose_of(c.g_wi_);
  wi_room_[k] = kernel::check_has_room(g_wi_[k]);
  moving_[k] = !c.V_wi_.isZero(0.0);
  init_[k] = c.st_.initialized;
  u_[k] = c.st_.u;
  sees_[k] = c.model_->usable(c.z_);
  // The pose models' measured pose, for their error on compact poses (ErrorModel::measured_pose).
  const SE3* g = sees_[k] ? c.model_->measured_pose(c.z_) : nullptr;
  pose_visual_[k] = g != nullptr;
  if (g) g_io_[k] = kernel::pose_of(*g);
  round0_[k] = c.round_;
  incarnation_[k] = c.incarnation_;
  // The first round's message (CameraObserver::publish).
  pub_[0][k] = kernel::compose(g_wi_[k], g_bar_[k]);
  pub_init_[0][k] = init_[k];
  return kernel::check_pose(pub_[0][k]) == MessageVerdict::accepted;
}

bool InProcessVmo::step(int p, int cur, const Measurement& z, double h, bool publish) {
  const auto k = static_cast<size_t>(p);
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
    if (sees_[k])
      visual = pose_visual_[k] ? kernel::pose_error(g_bar_[k], g_io_[k])
                               : model_->error(kernel::to_se3(g_bar_[k]), z, s_->features);
    u_[k] = kernel::vmo_input(*s_, mutual, sees_[k] ? &visual : nullptr);
    // Static camera (V_wi = 0): frames with a moving camera never reach this loop (run()).
    static const Vec6 still = Vec6::Zero();
    g_bar_[k] = kernel::integrate(g_bar_[k], still, u_[k], h, &unit);
  }
  if (!publish) return true;
  pub_[1 - cur][k] = kernel::compose(g_wi_[k], g_bar_[k]);
  return publish_message(k, cur, unit);
}

bool InProcessVmo::publish_message(size_t k, int cur, bool unit) {
  const auto& next = pub_[1 - cur][k];
  pub_init_[1 - cur][k] = init_[k];
  // CameraObserver::receive's check, which accepts every finite product of a camera pose with
  // room and a rotation fresh from the quaternion (kernel::check_has_room).
  if (unit && wi_room_[k]) return kernel::finite(next);
  return kernel::check_pose(next) == MessageVerdict::accepted;
}

bool InProcessVmo::step_pair(int p, int cur, const std::vector<Measurement>& z, double h,
                             bool publish) {
  const auto k = static_cast<size_t>(p), k1 = k + 1;
  const auto lane_fits = [&](size_t c) { return init_[c] && (!sees_[c] || pose_visual_[c]); };
  if (!lane_fits(k) || !lane_fits(k1)) {  // step() for each (both run)
    const bool first = step(p, cur, z[static_cast<size_t>(order_[k])], h, publish);
    const bool second = step(p + 1, cur, z[static_cast<size_t>(order_[k1])], h, publish);
    return first && second;
  }
  // step()'s initialised branch, both cameras at once (Vmo::step: (eq:EsRRBM) with
  // (eq:input_f-)).
  const auto& P = pub_[cur];
  const auto& P_init = pub_init_[cur];
  kernel::PoseSum nb[2];
  for (size_t l = 0; l < 2; ++l)
    for (int a = offset_[k + l]; a < offset_[k + l + 1]; ++a) {
      const auto j = static_cast<size_t>(nbr_[static_cast<size_t>(a)]);
      if (P_init[j]) nb[l].add(P[j]);
    }
  auto mutual = kernel::mutual_sum(
      kernel::pack(P[k], P[k1]), kernel::pack(nb[0].sum, nb[1].sum),
      kernel::X2{static_cast<double>(nb[0].count), static_cast<double>(nb[1].count)});
  const auto none = kernel::mask2(nb[0].count == 0, nb[1].count == 0);  // mutual term zero
  for (int r = 0; r < 6; ++r) mutual(r) = kernel::select(none, kernel::X2{0.0, 0.0}, mutual(r));
  const auto g_bar = kernel::pack(g_bar_[k], g_bar_[k1]);
  const auto sees = kernel::mask2(sees_[k] != 0, sees_[k1] != 0);
  // Where one of the two does not see, it takes its own estimate as the measured pose: its lane's
  // visual error is computed and not used.
  const auto u =
      !sees_[k] && !sees_[k1]
          ? kernel::vmo_input(*s_, mutual, mutual, sees)
          : kernel::vmo_input(
                *s_, mutual,
                kernel::pose_error(g_bar, kernel::pack(sees_[k] ? g_io_[k] : g_bar_[k],
                                                       sees_[k1] ? g_io_[k1] : g_bar_[k1])),
                sees);
  kernel::unpack(u, u_[k], u_[k1]);
  auto g = kernel::right_step(g_bar, u, h);  // static cameras (run())
  const kernel::X2 n = kernel::orthonormalise(g.R);
  kernel::unpack(g, g_bar_[k], g_bar_[k1]);
  if (!publish) return true;
  kernel::unpack(kernel::compose(kernel::pack(g_wi_[k], g_wi_[k1]), g), pub_[1 - cur][k],
                 pub_[1 - cur][k1]);
  const bool first = publish_message(k, cur, n[0] >= 1.0 && kernel::finite(g_bar_[k]));
  const bool second = publish_message(k1, cur, n[1] >= 1.0 && kernel::finite(g_bar_[k1]));
  return first && second;
}

void InProcessVmo::keep(int cur) {
  std::swap(kept_, pub_[cur]);  // (both buffers are written before they are read again)
  std::swap(kept_init_, pub_init_[cur]);
  std::swap(kept_incarnation_, incarnation_);  // (gather writes incarnation_ again)
}

void InProcessVmo::write_back(std::vector<CameraObserver>& cams, int p, int done) {
  const auto k = static_cast<size_t>(p);
  auto& c = cams[static_cast<size_t>(order_[k])];
  c.st_.g_bar = kernel::to_se3(g_bar_[k]);
  c.st_.u = u_[k];
  c.st_.initialized = init_[k];
  c.round_ = round0_[k] + static_cast<std::uint64_t>(done);
  kept_round_[k] = c.round_;  // its last message's round
  c.latest_.defer(this, p);
}

void InProcessVmo::fill(int position, std::vector<std::optional<EstimateMessage>>& slots) const {
  const auto k = static_cast<size_t>(position);
  // What CameraObserver::receive stored of each neighbour's message of the last round.
  for (int a = offset_[k]; a < offset_[k + 1]; ++a) {
    const auto j = static_cast<size_t>(nbr_[static_cast<size_t>(a)]);
    auto& slot = slots[static_cast<size_t>(a - offset_[k])];
    auto& kept = slot.has_value() ? *slot : slot.emplace();
    kept.sender = order_[j];
    kept.round = kept_round_[j];
    kept.stamp = 0.0;
    kept.initialized = kept_init_[j];
    kept.incarnation = kept_incarnation_[j];
    kept.g_w = kernel::to_se3(kept_[j]);
  }
}

int InProcessVmo::run(std::vector<CameraObserver>& cams, const std::vector<Measurement>& z,
                      int rounds, double h, WorkerPool* pool, bool check_stored) {
  s_ = &cams.front().settings();
  model_ = &cams.front().error_model();
  std::atomic<bool> refused{false};
  int done = 0, cur = 0;
  // The rounds run over positions p (breadth_first_order); the passes that touch the cameras
  // themselves (gather, write_back) over cameras i, which are large: in memory order.
  for_each(pool, n_, [&](int i) {
    const auto p = position_[static_cast<size_t>(i)];
    auto& c = cams[static_cast<size_t>(i)];
    c.set_measurement(z[static_cast<size_t>(i)]);
    if (!gather(c, p)) refused.store(true, std::memory_order_relaxed);
  });
  const auto write_back_all = [&](int done_rounds) {
    keep(cur);
    for_each(pool, n_,
             [&](int i) { write_back(cams, position_[static_cast<size_t>(i)], done_rounds); });
  };
  if (check_stored)  // CameraObserver::receive's out-of-order test on the first round's messages
    for_each(pool, n_, [&](int p) {
      const auto k = static_cast<size_t>(p);
      const auto& latest = cams[static_cast<size_t>(order_[k])].latest();
      for (int a = offset_[k]; a < offset_[k + 1]; ++a) {
        const auto j = static_cast<size_t>(nbr_[static_cast<size_t>(a)]);
        const auto& slot = latest[static_cast<size_t>(a - offset_[k])];
        if (slot && (incarnation_[j] < slot->incarnation ||
                     (incarnation_[j] == slot->incarnation && round0_[j] + 1 <= slot->round)))
          refused.store(true, std::memory_order_relaxed);
      }
    });
  if (refused) return 0;
  // A moving camera's believed pose moves on over the sub-steps (CameraObserver::step); those
  // frames take the camera-by-camera loop.
  if (std::any_of(moving_.begin(), moving_.end(), [](unsigned char m) { return m != 0; })) return 0;

  if (rounds <= 0) {
    write_back_all(done);
    return 0;
  }
  // Each round runs over pairs of positions (step_pair), the last position of an odd count alone.
  const auto round = [&](bool publish) {
    for_each(pool, (n_ + 1) / 2, [&](int q) {
      const int p = 2 * q;
      const bool ok =
          p + 1 < n_
              ? step_pair(p, cur, z, h, publish)
              : step(p, cur, z[static_cast<size_t>(order_[static_cast<size_t>(p)])], h, publish);
      if (!ok) refused.store(true, std::memory_order_relaxed);
    });
  };
  try {
    while (done + 1 < rounds) {
      round(true);
      ++done;
      if (refused) {  // the next round runs the per-camera way
        write_back_all(done);
        return done;
      }
      cur = 1 - cur;
    }
    // The last round publishes nothing, so the neighbours' messages it reads (buffer cur) stay
    // as they are for the write-back after it.
    round(false);
    write_back_all(++done);
    return done;
  } catch (...) {
    const auto error = std::current_exception();
    write_back_all(++done);
    std::rethrow_exception(error);
  }
}

}  // namespace netvmo::obs
