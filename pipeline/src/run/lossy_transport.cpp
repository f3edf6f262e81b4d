// "lossy": in-process delivery where each message to each neighbour is lost with probability
// `drop` (seeded, so runs repeat). A receiver keeps the last estimate it accepted from a
// neighbour, so a loss means a stale estimate in its mutual term for that round.
#include <random>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/run/transports.hpp"

namespace netvmo::run {
namespace {

class LossyTransport final : public obs::Transport {
 public:
  LossyTransport(const obs::Graph& g, double drop, std::uint64_t seed)
      : inner_(g), drop_(drop), rng_(seed) {}
  void send(const obs::EstimateMessage& m) override { inner_.send(m); }
  void receive(int receiver, std::vector<obs::EstimateMessage>& out) override {
    inner_.receive(receiver, out);
    std::bernoulli_distribution lost(drop_);
    size_t kept = 0;
    for (size_t k = 0; k < out.size(); ++k)
      if (!lost(rng_)) out[kept++] = out[k];
    out.resize(kept);
  }

 private:
  obs::InProcessTransport inner_;
  double drop_;
  std::mt19937_64 rng_;
};

}  // namespace

namespace transports {
const TransportKind& lossy() {
  static const TransportKind kind{
      "lossy", "in process, each message lost with probability --drop (seeded by --seed)",
      [](const obs::Graph& g, const TransportSettings& s) -> std::unique_ptr<obs::Transport> {
        if (!(s.drop >= 0.0 && s.drop < 1.0))
          throw InputError("transport lossy: drop probability " + std::to_string(s.drop) +
                           " is outside [0, 1)");
        return std::make_unique<LossyTransport>(g, s.drop, s.seed);
      }};
  return kind;
}
}  // namespace transports

}  // namespace netvmo::run
