// ClockSync (the neighbours' clock offsets from the estimate exchange's own timing, NTP's on-wire
// formulas, RFC 5905 section 8) and align_clocks (every camera's clock on the reference camera's,
// chained along the paths of least summed bound): closed forms, the bound |theta - true| <=
// delta / 2 on simulated exchanges with random transits, and the estimate message's seed corpus
// in the current wire format.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>

#include "NetvmoEstimate.h"
#include "netvmo/pipeline/net/clock_sync.hpp"
#include "netvmo/pipeline/ros/cdr.hpp"

using namespace netvmo::net;
namespace fs = std::filesystem;

namespace {

// Two cameras, 0 and 1, whose clocks read true time + their offset; messages cross with the
// given transits. Each send carries the sender's echoes, as DdsTransport's.
struct Pair {
  double offset[2] = {0.0, 0.0};
  ClockSync sync[2] = {ClockSync(0, {1}), ClockSync(1, {0})};
  double clock(int cam, double t) const { return t + offset[cam]; }
  // Camera `from` writes at true time t; the other takes it `transit` later.
  void message(int from, double t, double transit) {
    const int to = 1 - from;
    const auto echoes = sync[from].echoes();
    sync[to].taken(from, clock(from, t), clock(to, t + transit), echoes.data(), echoes.size());
  }
};

}  // namespace

// t1 = 10 (camera 0), transit 4 ms to camera 1 whose clock is 2 s ahead: t2 = 12.004; camera 1
// holds it 6 ms, t3 = 12.010; transit back 2 ms: t4 = 10.012. theta = ((t2 - t1) + (t3 - t4)) / 2
// = (2.004 + 1.998) / 2 = 2.001 (true 2, off by (4 - 2) / 2 ms), delta = 0.012 - 0.006 = 0.006.
TEST(ClockSync, OnWireFormulasClosedForm) {
  Pair p;
  p.offset[1] = 2.0;
  p.message(0, 10.0, 0.004);    // t1 = 10, t2 = 12.004
  p.message(1, 10.010, 0.002);  // t3 = 12.010, t4 = 10.012
  const auto o = p.sync[0].offset(1);
  ASSERT_TRUE(o);
  ASSERT_TRUE(o->round_trip());
  EXPECT_NEAR(o->offset_s, 2.001, 1e-9);
  EXPECT_NEAR(o->delay_s, 0.006, 1e-9);
  EXPECT_EQ(o->round_trips, 1u);
  // Camera 1 has no round trip yet: its one-way bound t3 - t4 of camera 0's message, 10 - 12.004.
  const auto back = p.sync[1].offset(0);
  ASSERT_TRUE(back);
  EXPECT_FALSE(back->round_trip());
  EXPECT_NEAR(back->offset_s, -2.004, 1e-9);
  // Stamps on camera 1's clock, on camera 0's: 2.001 earlier.
  EXPECT_NEAR(p.sync[0].to_own_clock(1, 100.0), 97.999, 1e-9);
  EXPECT_EQ(p.sync[0].to_own_clock(7, 100.0), 100.0);  // not a neighbour: unchanged
}

// Symmetric transits: the offset exactly, whatever the holding times.
TEST(ClockSync, SymmetricTransitsGiveTheOffsetExactly) {
  Pair p;
  p.offset[0] = -0.040;
  p.offset[1] = 0.040;
  double t = 1000.0;
  for (int k = 0; k < 20; ++k) {
    p.message(k % 2, t, 0.003);
    t += 0.0017 * (1 + k % 3);
  }
  for (int c = 0; c < 2; ++c) {
    const auto o = p.sync[c].offset(1 - c);
    ASSERT_TRUE(o && o->round_trip());
    EXPECT_NEAR(o->offset_s, p.offset[1 - c] - p.offset[c], 1e-9) << "camera " << c;
    EXPECT_NEAR(o->delay_s, 0.006, 1e-9);
  }
}

// Random transits (0.05 to 20 ms, seeded) and holding times: after every message each camera's
// estimate lies within delta / 2 of the truth, and the sample kept is the one of least delay.
TEST(ClockSync, EstimateStaysWithinHalfTheDelayOfTheTruth) {
  std::mt19937 rng(20261202);
  std::uniform_real_distribution<double> transit(0.00005, 0.020), hold(0.0, 0.010);
  Pair p;
  p.offset[0] = 1.7;
  p.offset[1] = -0.3;
  double t = 5000.0;
  double least[2] = {INFINITY, INFINITY};
  // The delay of the round trip each message closes, recomputed from the truth.
  double last_sent[2] = {NAN, NAN}, last_taken[2] = {NAN, NAN};  // true times
  for (int k = 0; k < 400; ++k) {
    const int from = rng() % 2 == 0 ? 0 : 1, to = 1 - from;
    const double d = transit(rng);
    // `from` echoes `to`'s last message: the round trip's two transits.
    if (!std::isnan(last_sent[to]) && !std::isnan(last_taken[from]))
      least[to] = std::min(least[to], (last_taken[from] - last_sent[to]) + d);
    p.message(from, t, d);
    last_sent[from] = t;
    last_taken[to] = t + d;
    for (int c = 0; c < 2; ++c) {
      const auto o = p.sync[c].offset(1 - c);
      if (!o || !o->round_trip()) continue;
      const double truth = p.offset[1 - c] - p.offset[c];
      EXPECT_LE(std::abs(o->offset_s - truth), o->delay_s / 2 + 1e-9) << "message " << k;
      EXPECT_NEAR(o->delay_s, least[c], 1e-9) << "message " << k;
    }
    t += d + hold(rng);
  }
  for (int c = 0; c < 2; ++c) EXPECT_GT(p.sync[c].offset(1 - c)->round_trips, 50u);
}

// A clock stepped back between the stamps gives a negative delay: ignored and counted.
TEST(ClockSync, NegativeDelayIsIgnored) {
  ClockSync s(0, {1});
  const ClockEcho echo{0, 100.0, 50.0};
  s.taken(1, 50.010, 99.0, &echo, 1);  // t4 = 99 < t1 = 100
  EXPECT_EQ(s.ignored(), 1u);
  EXPECT_FALSE(s.offset(1)->round_trip());
}

// Cameras 0-1-2 in a triangle (the direct edge 0-2 with a large bound, so 2 is reached through
// 1), 3 hanging off 2, 4 joined by one-way samples only, 5 by nothing.
TEST(AlignClocks, ChainsAlongTheLeastBoundAndReportsTheUnknown) {
  const auto link = [](int by, int of, double offset, double delay) {
    ClockLink l;
    l.by = by;
    l.of = of;
    l.offset.offset_s = offset;
    l.offset.delay_s = delay;
    l.offset.round_trips = 1;
    return l;
  };
  const std::vector<ClockLink> links = {
      link(0, 1, 0.0400, 0.0002),   // clock_1 - clock_0
      link(2, 1, 0.0800, 0.0004),   // clock_1 - clock_2: clock_2 = clock_0 - 0.04
      link(0, 2, -0.0300, 0.0200),  // the direct edge, bound 10 ms: not taken
      link(1, 0, -0.0401, 0.0010),  // the same edge from the other end, larger delay: not taken
      link(3, 2, -2.0000, 0.0006),  // clock_2 - clock_3: clock_3 = clock_2 + 2
      link(4, 3, 0.0, INFINITY),    // one way only
  };
  const auto a = align_clocks(6, 0, links);
  ASSERT_EQ(a.offset_s.size(), 6u);
  EXPECT_EQ(*a.offset_s[0], 0.0);
  EXPECT_NEAR(*a.offset_s[1], 0.04, 1e-12);
  EXPECT_NEAR(*a.bound_s[1], 0.0001, 1e-12);
  EXPECT_NEAR(*a.offset_s[2], -0.04, 1e-12);
  EXPECT_NEAR(*a.bound_s[2], 0.0003, 1e-12);
  EXPECT_NEAR(*a.offset_s[3], 1.96, 1e-12);
  EXPECT_NEAR(*a.bound_s[3], 0.0006, 1e-12);
  EXPECT_FALSE(a.offset_s[4]);
  EXPECT_FALSE(a.offset_s[5]);
  EXPECT_NEAR(a.correction_s[3], 1.96, 1e-12);
  EXPECT_EQ(a.correction_s[4], 0.0);
  // An offset within its bound of 0 is not corrected: the exchange cannot tell it from 0.
  const auto b = align_clocks(2, 0, {link(0, 1, 0.00004, 0.0001)});
  EXPECT_NEAR(*b.offset_s[1], 0.00004, 1e-15);
  EXPECT_EQ(b.correction_s[1], 0.0);
  const auto c = align_clocks(2, 0, {link(0, 1, 0.00006, 0.0001)});
  EXPECT_NEAR(c.correction_s[1], 0.00006, 1e-15);
}

// Every seed of the estimate message's fuzz corpus but the Cyclone regression decodes in the
// current wire format (a seed of an older format would only exercise the rejection of short
// payloads), and the seeds carry echoes and consensus states.
TEST(EstimateCorpus, SeedsDecodeInTheCurrentFormat) {
  const fs::path dir = fs::path(NETVMO_SOURCE_DIR) / "tests/fuzz/corpus/estimate_message";
  int seeds = 0;
  std::uint32_t echoes = 0, states = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().rfind("cyclone_", 0) == 0) continue;
    std::ifstream in(e.path(), std::ios::binary);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    netvmo::ros::Decoded<netvmo_msg_Estimate> m(netvmo_msg_Estimate_desc);
    std::string why;
    const bool ok = m.read(bytes.data(), bytes.size(), why);
    EXPECT_TRUE(ok) << e.path().filename() << ": " << why;
    if (ok) {
      echoes += m->echoes._length;
      states += m->state._length;
    }
    ++seeds;
  }
  EXPECT_GE(seeds, 6);
  EXPECT_GE(echoes, 5u);
  EXPECT_GE(states, 26u * 5);  // (the consensus state)
}
