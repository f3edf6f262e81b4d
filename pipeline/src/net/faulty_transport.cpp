#include "netvmo/pipeline/net/faulty_transport.hpp"

namespace netvmo::net {

FaultyTransport::FaultyTransport(obs::Transport& inner, double drop, double delay_s,
                                 std::uint64_t seed, std::function<double()> now)
    : inner_(inner), drop_(drop), delay_s_(delay_s), rng_(seed), now_(std::move(now)) {}

void FaultyTransport::receive(int receiver, std::vector<obs::EstimateMessage>& out) {
  inner_.receive(receiver, arrived_);
  const double now = now_();
  for (const auto& m : arrived_) {
    if (drop_ > 0 && uniform_(rng_) < drop_)  // (no draw without drops)
      ++dropped_;
    else
      delayed_.emplace_back(now + delay_s_, m);
  }
  out.clear();
  while (!delayed_.empty() && delayed_.front().first <= now) {
    out.push_back(std::move(delayed_.front().second));
    delayed_.pop_front();
  }
}

}  // namespace netvmo::net
