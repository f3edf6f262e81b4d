// The in-process fast path of NetworkedObserver for the paper's estimator (vmo): the same
// exchange rounds and the same arithmetic as n CameraObservers publishing and receiving each
// round (pose_kernel.hpp), on a compact structure-of-arrays copy of their state.
//
// Per frame: the cameras' state is gathered once (estimate, believed pose, velocity, flags); each
// round every camera reads its neighbours' estimates of the previous round directly from a
// contiguous array of world-frame poses (12 doubles each; CSR adjacency, no message copies), steps,
// and writes its own next estimate into the other half of a double buffer, so a round is one pass
// over the cameras and one barrier; the pass steps two neighbouring positions at once, one per
// lane of the kernel's two-camera arithmetic (step_pair). Every published pose is checked once
// (CameraObserver's check, which each of its receivers would apply alike; for a pose fresh from the
// Euler step, whose rotation is a unit quaternion's, a finiteness test gives the same verdict, see
// kernel::check_has_room). At the end of the frame the cameras' state and round counters are
// written back exactly as the per-camera exchange leaves them, and their latest neighbour
// messages are kept here and written into each camera when first read (fill(),
// CameraObserver::NeighbourMessages), so CameraObserver's API (latest(), input(), estimate()) is
// unchanged.
//
// The fast path runs a frame only when the result is provably the per-camera exchange's: every
// published pose passes the check (a refused message makes the rest of the frame run the
// per-camera way, see run()), no stored neighbour message could make a new one out of order, and
// no camera moves (CameraObserver::step moves a moving camera's believed pose every sub-step).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/worker_pool.hpp"
#include "pose_kernel.hpp"

namespace netvmo::obs {

class InProcessVmo {
 public:
  explicit InProcessVmo(const Graph& graph);

  /// Whether the fast path can run the estimator these cameras use (vmo).
  static bool supports(const CameraObserver& camera);

  /// Sets each camera's measurement z[i] (CameraObserver::set_measurement) and runs up to
  /// `rounds` exchange rounds of length h on the cameras, on the pool's threads when there is
  /// one, and writes the state back (the last round's state right after each camera's step: that
  /// round publishes nothing). Returns the rounds
  /// done: fewer when a camera published a pose that its neighbours refuse, or when a stored
  /// message would make one out of order (`check_stored`: look; otherwise known not to), and none
  /// when a camera moves (V_wi != 0: its believed pose moves over the sub-steps); the
  /// caller then runs the remaining rounds the per-camera way. Rethrows the error model's
  /// exception of the smallest camera index after writing back.
  int run(std::vector<CameraObserver>& cams, const std::vector<Measurement>& z, int rounds,
          double h, WorkerPool* pool, bool check_stored);

  /// Writes the neighbours' messages of the last frame written back to the camera at `position`
  /// into its slots (what CameraObserver::receive stored of each): the cameras' deferred
  /// latest() (CameraObserver::NeighbourMessages).
  void fill(int position, std::vector<std::optional<EstimateMessage>>& slots) const;

 private:
  /// f(0), ..., f(count - 1), on the pool's threads when there is one.
  void for_each(WorkerPool* pool, int count, const std::function<void(int)>& f) const;
  /// Loads camera c into position p and publishes its first estimate; false when the pose would
  /// be refused.
  bool gather(const CameraObserver& c, int p);
  /// One round of the camera at position p: reads buffer `cur`, writes buffer 1 - cur (when
  /// `publish`); false when the published pose would be refused.
  bool step(int p, int cur, const Measurement& z, double h, bool publish);
  /// One round of the cameras at positions p and p + 1 (z by camera): both at once, one per lane
  /// of the kernel's two-camera arithmetic (kernel::Pose2), when both are initialised and see
  /// through a pose model or not at all (the usual case); otherwise each by step(). The same bits
  /// either way; false when either published pose would be refused.
  bool step_pair(int p, int cur, const std::vector<Measurement>& z, double h, bool publish);
  /// Writes the camera at position k's message of the round into buffer 1 - cur and checks it as
  /// its receivers would (`unit`: its rotation is fresh from kernel::orthonormalise with
  /// |q|^2 >= 1 and the pose finite); false when it would be refused.
  bool publish_message(size_t k, int cur, bool unit);
  /// Writes the camera at position p back after `done` rounds, its neighbours' messages
  /// deferred to the kept ones (keep()).
  void write_back(std::vector<CameraObserver>& cams, int p, int done);
  /// Keeps the messages of buffer cur as the ones the cameras last received (fill()).
  void keep(int cur);

  int n_;
  /// order_[p]: the camera at position p of every array below (breadth-first: neighbours near
  /// each other, each thread a contiguous part of the positions).
  std::vector<int> order_;
  std::vector<int> position_;            ///< position_[i]: camera i's position
  const ObserverSettings* s_ = nullptr;  ///< the cameras' settings (the network's: all alike)
  const ErrorModel* model_ = nullptr;
  /// CSR by position: the positions of N_order_[p] = nbr_[offset_[p], offset_[p + 1]).
  std::vector<int> offset_, nbr_;
  std::vector<kernel::Pose> g_bar_, g_wi_;
  std::vector<kernel::Pose> pub_[2];        ///< g_wi g_bar_i of the round, double-buffered
  std::vector<unsigned char> pub_init_[2];  ///< the published `initialized` flag
  std::vector<unsigned char> init_, moving_, sees_, refused_;
  std::vector<unsigned char> wi_room_;  ///< kernel::check_has_room(g_wi)
  /// The camera sees and its error model's error is kernel::pose_error(g_bar, g_io_): the
  /// pose models (ErrorModel::measured_pose), whose error() gives the same bits.
  std::vector<unsigned char> pose_visual_;
  std::vector<kernel::Pose> g_io_;
  std::vector<Vec6> u_;
  std::vector<std::uint64_t> round0_, incarnation_;
  /// The messages of the last round that published of the last frame written back, by sender
  /// position (pose, initialized flag, round, incarnation): what the cameras' deferred latest()
  /// holds.
  std::vector<kernel::Pose> kept_;
  std::vector<unsigned char> kept_init_;
  std::vector<std::uint64_t> kept_round_, kept_incarnation_;
};

}  // namespace netvmo::obs
