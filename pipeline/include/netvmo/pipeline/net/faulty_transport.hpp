// Faults of a network, injected on one camera's receiving side of another transport (a decorator,
// as the in-process `lossy` transport is one of direct delivery): every message that arrives is
// lost with probability `drop` (seeded), the others are handed on `delay_s` seconds of the given
// clock after they arrived, in arrival order. `netvmo node`'s asynchronous mode uses it for
// --drop, --delay and --seed.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <utility>
#include <vector>

#include "netvmo/observer/transport.hpp"

namespace netvmo::net {

class FaultyTransport final : public obs::Transport {
 public:
  /// `inner` outlives this; `now` gives the current time [s] (the delays' clock).
  FaultyTransport(obs::Transport& inner, double drop, double delay_s, std::uint64_t seed,
                  std::function<double()> now);
  void send(const obs::EstimateMessage& m) override { inner_.send(m); }
  /// The messages whose delay has passed, after taking in what `inner` has for `receiver`.
  void receive(int receiver, std::vector<obs::EstimateMessage>& out) override;
  /// Messages lost so far.
  std::uint64_t dropped() const { return dropped_; }

 private:
  obs::Transport& inner_;
  double drop_, delay_s_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::function<double()> now_;
  std::vector<obs::EstimateMessage> arrived_;
  std::deque<std::pair<double, obs::EstimateMessage>> delayed_;  ///< (due, message)
  std::uint64_t dropped_ = 0;
};

}  // namespace netvmo::net
