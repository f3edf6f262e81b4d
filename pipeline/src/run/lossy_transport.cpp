// "lossy": in-process delivery where each message to each neighbour is lost with probability
// `drop` (seeded, so runs repeat). A receiver keeps the last estimate it accepted from a
// neighbour, so a loss means a stale estimate in its mutual term for that round.
#include <random>

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
namespace {
class Lossy final : public TransportKind {
 public:
  std::string_view name() const override { return "lossy"; }
  std::string_view description() const override {
    return "in process, each message lost with probability --drop (seeded by --seed)";
  }
  std::vector<TransportParameter> parameters() const override {
    return {{"drop", "lossy transport: probability that a message is lost", 0.0, 0.0, 0.99},
            {"seed", "lossy transport: seed of the losses", 1.0, 0.0, 9007199254740992.0, true}};
  }
  std::unique_ptr<obs::Transport> make(const obs::Graph& g,
                                       const std::map<std::string, double>& v) const override {
    return std::make_unique<LossyTransport>(g, v.at("drop"),
                                            static_cast<std::uint64_t>(v.at("seed")));
  }
};
}  // namespace

const TransportKind& lossy() {
  static const Lossy kind;
  return kind;
}
}  // namespace transports

}  // namespace netvmo::run
