// One exchange round of the networked observer, written once for every way cameras are run: n in
// one process (NetworkedObserver, over any Transport) or one per process (the pipeline's node,
// over DDS). The round gives each camera i the neighbours' estimates g_wj g_bar_j of the mutual
// term of (eq:input_f-) and then advances it; for every camera it is
//   1. send_estimate:  i publishes g_wi g_bar_i (round, stamp, consensus state) to its
//                      neighbours through the transport;
//   2. take_estimates: i takes in the messages that reached it (each checked by
//                      CameraObserver::receive) and, with a staleness bound, forgets the
//                      neighbours whose latest estimate is older than the bound;
//   3. CameraObserver::step(h): i advances on its neighbours' estimates of the previous round.
// Every camera of a round sends before any camera takes: NetworkedObserver runs step 1 for all
// cameras, then 2 and 3; a process of its own waits in 2 (a lock-step transport blocks until
// the round's messages have come) or takes what has come (asynchronous).
#pragma once

#include <optional>
#include <vector>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/transport.hpp"

namespace netvmo::obs {

/// Step 1: camera c publishes this round's estimate (CameraObserver::publish, with `stamp` on
/// the sender's clock [s]) and sends it to its neighbours.
void send_estimate(CameraObserver& c, Transport& t, double stamp = 0.0);

/// A staleness bound for take_estimates: a neighbour whose latest accepted estimate is stamped
/// more than `bound` [s] before `now` (both on the receiver's clock) leaves the mutual term until
/// it is heard again (CameraObserver::forget; a switching graph).
struct Staleness {
  double now = 0.0;    ///< the receiver's time of this round [s]
  double bound = 0.0;  ///< the largest age kept [s]
};

/// What take_estimates did.
struct TakeReport {
  int received = 0;   ///< messages the transport handed over (accepted or refused)
  int forgotten = 0;  ///< neighbours forgotten as stale
};

/// Step 2: the messages that reached camera c since its last call (Transport::receive, into the
/// scratch `inbox`), each taken in by c.receive() in the order delivered; then, with a staleness
/// bound, the neighbours older than it are forgotten.
TakeReport take_estimates(CameraObserver& c, Transport& t, std::vector<EstimateMessage>& inbox,
                          const std::optional<Staleness>& stale = std::nullopt);

/// A camera that joins a running network late (a restarted process) starts from the average of
/// its neighbours' estimates (ObserverSettings::init_from_neighbours), as a blind camera does,
/// so that none of them jumps: it steps (and so initialises and publishes) only once it holds an
/// estimate of every neighbour, and holds its own measurement back until then. If a neighbour
/// stays silent (blind and uninitialised, or gone), both wait until `until`; it then starts from
/// those it has heard, or, having heard none, from its own measurement. Started from one
/// neighbour with its measurement in use, a late joiner's visual term would weigh k_e against
/// k_s times that one neighbour instead of all d_i: its estimate would go k_e / (k_e + k_s) of the
/// way to its own measurement instead of k_e / (k_e + k_s d_i) (eq:input_f-), and the neighbours
/// would follow it once they hear it. Over DDS the neighbours' streams to a late joiner do not
/// start together: a reliable stream whose first samples were missed resumes when the writer's
/// next heartbeat has them sent again (docs/processes.md, "Kill and restart").
struct JoinHold {
  bool held = false;   ///< a late join: stepping and the measurement are held back
  double until = 0.0;  ///< [s] from which neither waits for a silent neighbour
  /// Set by release() at `until` when some neighbours were heard: it waits for one more step
  /// (from those) before the measurement, used then whether or not that step initialised c.
  bool stepped_past_until = false;
  /// Whether c steps at `now` (after the round's messages are in): not held, every neighbour's
  /// latest estimate initialised, or `now` >= `until`.
  bool may_step(const CameraObserver& c, double now) const;
  /// True once: at the first `now` at which c may use its measurement (before the round's
  /// step): once it has started from its neighbours (it steps only as may_step says); from
  /// `until` on, having heard none (it then starts from its measurement), or one step after
  /// `until` whether that step started it or not (an estimator that starts only from its own
  /// measurement must not wait for ever). False before and after.
  bool release(const CameraObserver& c, double now);
};

}  // namespace netvmo::obs
