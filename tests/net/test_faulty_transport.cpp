// The faults `netvmo node` injects on its receiving side (FaultyTransport), on a scripted inner
// transport and a clock of the test's own: drops are seeded and drawn only when asked for, and
// every message kept comes out `delay` later, in arrival order.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "netvmo/pipeline/net/faulty_transport.hpp"

namespace netvmo {
namespace {

// Hands out the messages given to it, once.
class Scripted final : public obs::Transport {
 public:
  std::vector<obs::EstimateMessage> next;
  void send(const obs::EstimateMessage&) override {}
  void receive(int, std::vector<obs::EstimateMessage>& out) override {
    out = next;
    next.clear();
  }
};

obs::EstimateMessage message(int sender, std::uint64_t round) {
  obs::EstimateMessage m;
  m.sender = sender;
  m.round = round;
  return m;
}

TEST(FaultyTransport, KeptMessagesComeOutDelayedInOrder) {
  Scripted inner;
  double now = 10.0;
  net::FaultyTransport t(inner, 0.0, 0.05, 1, [&] { return now; });
  std::vector<obs::EstimateMessage> out;
  inner.next = {message(1, 1), message(2, 1)};
  t.receive(0, out);
  EXPECT_TRUE(out.empty());  // not due yet
  now = 10.03;
  inner.next = {message(1, 2)};
  t.receive(0, out);
  EXPECT_TRUE(out.empty());
  now = 10.05;  // the first two are due, the third not
  t.receive(0, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].sender, 1);
  EXPECT_EQ(out[1].sender, 2);
  now = 10.08;
  t.receive(0, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].round, 2u);
  EXPECT_EQ(t.dropped(), 0u);
}

TEST(FaultyTransport, DropsAreSeededAndDrawnOnePerMessage) {
  const int messages = 4000;
  const double drop = 0.3;
  const std::uint64_t seed = 77;
  Scripted inner;
  net::FaultyTransport t(inner, drop, 0.0, seed, [] { return 0.0; });
  std::vector<obs::EstimateMessage> out;
  size_t kept = 0;
  for (int k = 0; k < messages; ++k) {
    inner.next = {message(k % 3, static_cast<std::uint64_t>(k))};
    t.receive(0, out);
    kept += out.size();
  }
  // The same draws as one uniform variate per message from the seed.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uint64_t expected = 0;
  for (int k = 0; k < messages; ++k) expected += u(rng) < drop;
  EXPECT_EQ(t.dropped(), expected);
  EXPECT_EQ(kept + t.dropped(), static_cast<size_t>(messages));
  // 3 standard deviations of the binomial count.
  EXPECT_NEAR(static_cast<double>(expected), drop * messages, 3 * std::sqrt(messages * 0.21));
}

}  // namespace
}  // namespace netvmo
