// Clocks that disagree: each node's offset to its neighbours, estimated from the estimate
// exchange itself as NTP does, and the merge's alignment of every node's rows onto one clock.
//
// Every estimate carries the time it was written on its sender's clock (`sent`) and, for each
// neighbour the sender has heard, an echo: that neighbour's latest `sent` and when the sender took
// it on its own clock. When camera i takes camera j's message at t4 (i's clock) carrying j's echo
// of i's own message (t1: i's `sent`, t2: when j took it, on j's clock) and j's `sent` t3, then
// (RFC 5905, section 8, "On-wire protocol")
//   offset  theta = ((t2 - t1) + (t3 - t4)) / 2   (clock_j - clock_i)
//   delay   delta = (t4 - t1) - (t3 - t2)         (the two transits, without j's holding time)
// and with constant clocks the true offset lies within delta / 2 of theta: theta - theta_true =
// (d_ij - d_ji) / 2 for the two one-way transits d >= 0 (each stamp is read before the message
// leaves or after it was taken), and delta = d_ij + d_ji. The sample of least delay is kept (NTP's
// clock filter, without its drift estimate: a run's clocks are taken as constant offsets).
// Before the first round trip, the one-way t3 - t4 <= theta (j's message needed d >= 0 to
// arrive) is the best bound known; it stands in for theta until one completes.
//
// The merge (align_clocks) chains the per-edge offsets from a reference camera along the path
// of least summed bound (Dijkstra over delta / 2); a camera's bound is the sum along its path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace netvmo::net {

/// The latest message of camera `camera`: its `sent` on its clock, and when it was taken on
/// the echoing camera's clock (mirrors netvmo::msg::Echo).
struct ClockEcho {
  int camera = 0;
  double sent = 0.0;
  double received = 0.0;
};

/// A neighbour's clock relative to this camera's: clock_neighbour - clock_self.
struct ClockOffset {
  double offset_s = 0.0;
  /// Round-trip delay of the sample kept (the offset is within delay_s / 2 of the truth);
  /// infinite while only one-way samples exist.
  double delay_s = 0.0;
  std::uint64_t round_trips = 0;  ///< round-trip samples taken
  bool round_trip() const;        ///< whether delay_s is finite (a bound exists)
};

/// One camera's offset estimates to its neighbours, fed by its transport (DdsTransport).
class ClockSync {
 public:
  /// `self`: this camera's index; `neighbours`: N_i (indices).
  ClockSync(int self, std::vector<int> neighbours);

  /// A message of neighbour `from`, written at `sent` on its clock and taken at `taken` on
  /// ours, carrying `echoes` (of which the one of this camera, if any, closes a round trip).
  /// A sample of negative delay (a clock stepped between the stamps) is ignored and counted.
  void taken(int from, double sent, double taken, const ClockEcho* echoes, std::size_t count);

  /// What this camera's next message echoes: each neighbour heard, its latest message.
  const std::vector<ClockEcho>& echoes() const { return echoes_; }

  /// Neighbour `j`'s offset; none before any of its messages was taken.
  std::optional<ClockOffset> offset(int j) const;

  /// `stamp` on neighbour j's clock expressed on this camera's clock (stamp - offset);
  /// unchanged while j's offset is unknown.
  double to_own_clock(int j, double stamp) const;

  /// Samples of negative delay ignored.
  std::uint64_t ignored() const { return ignored_; }

 private:
  struct Link {
    bool heard = false;
    double one_way = 0.0;  ///< max of t3 - t4 over j's messages (a lower bound of the offset)
    ClockOffset best;      ///< round trip of least delay (best.round_trips counts them all)
  };
  int self_;
  std::vector<int> neighbours_;
  std::vector<Link> links_;        ///< by neighbour, in neighbours_' order
  std::vector<ClockEcho> echoes_;  ///< by neighbour heard, in the order first heard
  std::uint64_t ignored_ = 0;
};

/// One node's report of a neighbour's clock (node_<id>.json "clock"): clock_of - clock_by.
struct ClockLink {
  int by = 0;  ///< the reporting camera's index
  int of = 0;  ///< its neighbour's index
  ClockOffset offset;
};

/// Every camera's clock on the reference camera's: offset_s = clock_i - clock_reference, within
/// bound_s of the truth; unknown for a camera joined to the reference by no chain of round trips.
struct ClockAlignment {
  int reference = 0;  ///< camera index
  std::vector<std::optional<double>> offset_s, bound_s;
  /// offset_s where it is farther than bound_s from 0, else 0 (the exchange cannot tell that
  /// clock from the reference's); 0 where unknown. What the merge subtracts from a camera's times.
  std::vector<double> correction_s;
};

/// The alignment of `cameras` clocks from the nodes' reports, chained from `reference` along the
/// paths of least summed bound (each edge's report of least delay, from either end).
ClockAlignment align_clocks(std::size_t cameras, int reference,
                            const std::vector<ClockLink>& links);

}  // namespace netvmo::net
