// The exchange round of exchange.hpp, written once: cameras run by hand with send_estimate /
// take_estimates / step (as a camera's own process runs them) reach bit for bit what the
// in-process NetworkedObserver reaches over a transport, and the staleness bound forgets exactly
// the neighbours older than it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <iterator>

#include "netvmo/observer/exchange.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"
#include "paper5.hpp"

using namespace netvmo::obs;

namespace {

// Delivers every message to the sender's neighbours, in the order sent (not an
// InProcessTransport: NetworkedObserver then runs every sub-step as an exchange round).
class Mailbox final : public Transport {
 public:
  explicit Mailbox(Graph g) : graph_(std::move(g)), mail_(size_t(graph_.size())) {}
  void send(const EstimateMessage& m) override {
    for (int j : graph_.neighbors(m.sender)) mail_[size_t(j)].push_back(m);
  }
  void receive(int receiver, std::vector<EstimateMessage>& out) override {
    out = std::move(mail_[size_t(receiver)]);
    mail_[size_t(receiver)].clear();
  }

 private:
  Graph graph_;
  std::vector<std::vector<EstimateMessage>> mail_;
};

Measurement seen(const netvmo::test::Paper5& p, int i) {
  Measurement m;
  if (i < 3) {  // cameras 1..3 see their fictitious targets
    m.delta = true;
    m.g_io_true = p.g_wi[size_t(i)].inverse() * p.g_wo[size_t(i)];
  }
  return m;
}

}  // namespace

TEST(Exchange, CamerasRunByHandEqualTheNetworkedObserverBitForBit) {
  const netvmo::test::Paper5 p;
  for (const char* estimator : {"vmo", "zero-offset"}) {
    SCOPED_TRACE(estimator);
    ObserverSettings s;
    s.estimator = estimator;
    const SE3 start = make_pose({0, 0, 1}, Vec3::Zero());
    std::vector<Measurement> z;
    for (int i = 0; i < 5; ++i) z.push_back(seen(p, i));

    NetworkedObserver ref(p.graph, s);
    ref.set_transport(std::make_unique<Mailbox>(p.graph));
    ref.set_camera_poses(p.g_wi);
    ref.reset(std::vector<SE3>(5, start));

    // Two sets of cameras run by hand: one through exchange.hpp as a camera's process runs it,
    // one with the transport and CameraObserver's publish / receive spelt out here (independent
    // of exchange.hpp, which the networked observer also uses).
    std::vector<CameraObserver> cams, raw;
    for (auto* set : {&cams, &raw})
      for (int i = 0; i < 5; ++i) {
        set->emplace_back(i, p.graph.neighbors(i), s, 5);
        set->back().set_camera_pose(p.g_wi[size_t(i)]);
        set->back().reset(start);
      }
    Mailbox net(p.graph), raw_net(p.graph);
    std::vector<EstimateMessage> inbox;
    const double dt = 1.0 / 30.0;
    const int N = ref.substeps(dt);
    for (int k = 0; k < 60; ++k) {
      ref.step(dt, z);
      for (int i = 0; i < 5; ++i) {
        cams[size_t(i)].set_measurement(z[size_t(i)]);
        raw[size_t(i)].set_measurement(z[size_t(i)]);
      }
      for (int r = 0; r < N; ++r) {
        for (auto& c : cams) send_estimate(c, net);
        for (auto& c : cams) {
          const TakeReport t = take_estimates(c, net, inbox);
          EXPECT_EQ(t.received, static_cast<int>(c.neighbours().size()));
          EXPECT_EQ(t.forgotten, 0);
        }
        for (auto& c : cams) c.step(dt / N);
        for (auto& c : raw) raw_net.send(c.publish());
        for (auto& c : raw) {
          raw_net.receive(c.index(), inbox);
          for (const auto& m : inbox) EXPECT_EQ(c.receive(m), MessageVerdict::accepted);
        }
        for (auto& c : raw) c.step(dt / N);
      }
    }
    // The estimates moved, and every camera is where the networked observer's is, exactly.
    EXPECT_GT((ref.camera(4).estimate_world().translation() - start.translation()).norm(), 1e-2);
    for (int i = 0; i < 5; ++i)
      for (const auto* set : {&cams, &raw})
        EXPECT_TRUE(((*set)[size_t(i)].estimate_world().matrix().array() ==
                     ref.camera(i).estimate_world().matrix().array())
                        .all())
            << "camera " << i + 1 << (set == &raw ? ", spelt out" : ", exchange.hpp");
  }
}

TEST(Exchange, TakeForgetsExactlyTheNeighboursOlderThanTheBound) {
  // Camera 0 with neighbours 1, 2, 3; they last spoke at t = 1.0, 1.5 and 1.9 s.
  const Graph g(4, {{0, 1}, {0, 2}, {0, 3}});
  CameraObserver c(0, g.neighbors(0), ObserverSettings{});
  Mailbox net(g);
  std::vector<CameraObserver> others;
  for (int j = 1; j <= 3; ++j) others.emplace_back(j, g.neighbors(j), ObserverSettings{});
  const double spoke[] = {1.0, 1.5, 1.9};
  for (int j = 0; j < 3; ++j) send_estimate(others[size_t(j)], net, spoke[j]);
  std::vector<EstimateMessage> inbox;
  // At t = 2.0 with a bound of 0.5 s: camera 1 (1.0 s old) goes; camera 2 (0.5 s) stays.
  const TakeReport t = take_estimates(c, net, inbox, Staleness{2.0, 0.5});
  EXPECT_EQ(t.received, 3);
  EXPECT_EQ(t.forgotten, 1);
  EXPECT_FALSE(c.latest()[0].has_value());
  ASSERT_TRUE(c.latest()[1].has_value());
  EXPECT_EQ(c.latest()[1]->stamp, 1.5);
  EXPECT_TRUE(c.latest()[2].has_value());
  // Nothing new at t = 2.45: camera 2 is now 0.95 s old and goes; camera 3 (0.55 s) goes too.
  const TakeReport later = take_estimates(c, net, inbox, Staleness{2.45, 0.5});
  EXPECT_EQ(later.received, 0);
  EXPECT_EQ(later.forgotten, 2);
  for (const auto& m : c.latest()) EXPECT_FALSE(m.has_value());
  // Without a bound nothing is forgotten, however old.
  send_estimate(others[0], net, 0.0);
  EXPECT_EQ(take_estimates(c, net, inbox).forgotten, 0);
  EXPECT_TRUE(c.latest()[0].has_value());
}

// JoinHold: a late joiner steps once it has heard every neighbour and then uses its
// measurement; a neighbour that stays silent is waited for until the bound, exactly once.
TEST(Exchange, AJoinHoldWaitsForEveryNeighbourThenTheBound) {
  const Graph g(4, {{0, 1}, {0, 2}, {0, 3}});
  ObserverSettings s;
  s.init_from_measurement = s.init_from_neighbours = true;
  std::vector<CameraObserver> others;
  for (int j = 1; j <= 3; ++j) {
    others.emplace_back(j, g.neighbors(j), s);
    others.back().set_initialized(true);
  }
  Mailbox net(g);
  std::vector<EstimateMessage> inbox;
  CameraObserver c(0, g.neighbors(0), s);
  c.set_initialized(false);
  JoinHold join{true, 1.0};
  EXPECT_FALSE(join.may_step(c, 0.0));  // nobody heard
  EXPECT_FALSE(join.release(c, 0.0));
  for (int j = 0; j < 2; ++j) send_estimate(others[size_t(j)], net, 0.1);
  take_estimates(c, net, inbox);
  EXPECT_FALSE(join.may_step(c, 0.1));  // camera 3 not heard yet
  EXPECT_FALSE(join.release(c, 0.1));
  send_estimate(others[2], net, 0.2);
  take_estimates(c, net, inbox);
  EXPECT_FALSE(join.release(c, 0.2));  // every neighbour heard, not yet started from them
  ASSERT_TRUE(join.may_step(c, 0.2));
  c.step(1e-3);
  ASSERT_TRUE(c.initialized());
  EXPECT_TRUE(join.release(c, 0.3));
  EXPECT_FALSE(join.held);
  EXPECT_FALSE(join.release(c, 0.4));  // once
  EXPECT_TRUE(join.may_step(c, 0.4));

  // A late joiner with settings `os` that has heard cameras 1 and 2, camera 3 silent.
  const auto heard_two = [&](const ObserverSettings& os) {
    CameraObserver o(0, g.neighbors(0), os);
    o.set_initialized(false);
    for (int j = 0; j < 2; ++j) send_estimate(others[size_t(j)], net, 0.5);
    take_estimates(o, net, inbox);
    return o;
  };
  // At the bound it starts from those two, then releases.
  CameraObserver some = heard_two(s);
  JoinHold wait{true, 1.0};
  EXPECT_FALSE(wait.may_step(some, 0.99));
  EXPECT_FALSE(wait.release(some, 1.0));  // heard some: start from them first
  ASSERT_TRUE(wait.may_step(some, 1.0));
  some.step(1e-3);
  ASSERT_TRUE(some.initialized());
  EXPECT_TRUE(wait.release(some, 1.0));
  // An observer that does not start from its neighbours: at the bound one step from those
  // heard, then its measurement all the same.
  ObserverSettings own = s;
  own.init_from_neighbours = false;
  CameraObserver lone = heard_two(own);
  JoinHold bound{true, 1.0};
  EXPECT_FALSE(bound.release(lone, 1.0));
  ASSERT_TRUE(bound.may_step(lone, 1.0));
  lone.step(1e-3);
  ASSERT_FALSE(lone.initialized());
  EXPECT_TRUE(bound.release(lone, 1.01));
  // Nobody heard: at the bound it uses its measurement (and starts from it).
  CameraObserver alone(0, g.neighbors(0), s);
  alone.set_initialized(false);
  JoinHold none_heard{true, 1.0};
  EXPECT_FALSE(none_heard.release(alone, 0.99));
  EXPECT_TRUE(none_heard.release(alone, 1.0));
  // Not a late join: it steps and has nothing to release.
  JoinHold none;
  EXPECT_TRUE(none.may_step(alone, 0.0));
  EXPECT_FALSE(none.release(c, 0.0));
}

// A late joiner whose neighbours' streams start apart (as a reliable DDS stream whose first
// samples were missed resumes only at the writer's next heartbeat): the paper's five cameras
// (k_e = 10, k_s = 100) converge for 1 s, camera 3 (index 2, neighbours 1, 2 and 4) is down for
// 5 frames (its neighbours keep its last estimate) and joins with a fresh observer, PnP-style
// initialisation (from its neighbours, else from its measurement). In the frame it joins, two of
// its neighbours' messages reach it only from the 16th of its 21 rounds on. With JoinHold its
// neighbours move in that frame by less than e, the lead a correctly joined camera 3 has on them
// in steady state (k_e / (k_e + k_s d_3) of the way to its fictitious target, eq:input_f-). Let
// in as soon as it has heard one neighbour (the rule before), it is coupled one way: it follows
// that neighbour alone, with its measurement weighed against that one (k_e / (k_e + k_s) of the
// way), while all three follow it, and it drags them along.
namespace {

// Mailbox whose messages from the `late` senders to `receiver` wait, while closed, until the
// receiver's first receive after open() (ahead of what was sent since, in the order sent).
class LateStreams final : public Transport {
 public:
  LateStreams(Graph g, int receiver, std::vector<int> late)
      : mail_(std::move(g)), receiver_(receiver), late_(std::move(late)) {}
  void send(const EstimateMessage& m) override { mail_.send(m); }
  void receive(int receiver, std::vector<EstimateMessage>& out) override {
    mail_.receive(receiver, out);
    if (receiver != receiver_) return;
    if (closed_) {
      const auto is_late = [&](const EstimateMessage& m) {
        return std::find(late_.begin(), late_.end(), m.sender) != late_.end();
      };
      std::copy_if(out.begin(), out.end(), std::back_inserter(held_), is_late);
      out.erase(std::remove_if(out.begin(), out.end(), is_late), out.end());
    } else if (!held_.empty()) {
      out.insert(out.begin(), held_.begin(), held_.end());
      held_.clear();
    }
  }
  void close() { closed_ = true; }
  void open() { closed_ = false; }

 private:
  Mailbox mail_;
  int receiver_;
  std::vector<int> late_;
  bool closed_ = false;
  std::vector<EstimateMessage> held_;
};

// How the late joiner is let in: JoinHold, or the rule before it (it steps from whoever it has
// heard and uses its measurement once initialised).
enum class Release { join_hold, once_initialised };

struct JoinMove {
  double move =
      0;  ///< the largest position change of camera 3's neighbours over its join frame [m]
  /// What a correctly joined camera 3 leads them by, at most: k_e / (k_e + k_s d_3) of the
  /// distance from its neighbours' average to its own fictitious target [m] (eq:input_f-).
  double e = 0;
};

JoinMove join_move(std::vector<int> late, Release rule) {
  const netvmo::test::Paper5 p;
  ObserverSettings s;
  s.k_e = 10;
  s.k_s = 100;
  s.init_from_measurement = s.init_from_neighbours = true;
  std::vector<Measurement> z;
  for (int i = 0; i < 5; ++i) {
    z.push_back(seen(p, i));
    if (z.back().delta) z.back().g_io_pnp = z.back().g_io_true;
  }
  const auto fresh = [&](int i) {
    CameraObserver c(i, p.graph.neighbors(i), s, 5);
    c.set_camera_pose(p.g_wi[size_t(i)]);
    c.reset(SE3::Identity());
    c.set_initialized(false);
    return c;
  };
  std::vector<CameraObserver> cams;
  for (int i = 0; i < 5; ++i) cams.push_back(fresh(i));
  cams[3].reset(make_pose({0, 0, 1}, Vec3::Zero()));  // camera 4, blind: a start of its own
  cams[3].set_initialized(true);
  cams[4].reset(make_pose({0, 0, 1}, Vec3::Zero()));
  cams[4].set_initialized(true);
  LateStreams net(p.graph, 2, late);
  std::vector<EstimateMessage> inbox;
  const double dt = 1.0 / 30.0;
  const int N = frame_substeps(dt, s, p.graph.max_degree());
  const int kJoin = 35;  // 30 frames up, 5 down
  JoinHold join{true, kJoin * dt + 0.5};
  std::vector<Vec3> before(5);
  for (int k = 0; k <= kJoin; ++k) {
    const bool down = k >= 30 && k < kJoin;
    if (k == kJoin) {
      cams[2] = fresh(2);
      cams[2].set_incarnation(1);  // a new process: its rounds count from 0 again
      for (int i = 0; i < 5; ++i)
        before[size_t(i)] = cams[size_t(i)].estimate_world().translation();
      net.close();
    }
    for (int i = 0; i < 5; ++i) {
      if (down && i == 2) continue;
      const bool held = k == kJoin && i == 2;
      cams[size_t(i)].set_measurement(held ? Measurement{} : z[size_t(i)]);
    }
    for (int r = 0; r < N; ++r) {
      const double t = k * dt + r * dt / N;
      if (k == kJoin && r == 15) net.open();
      if (k == kJoin) {
        bool release = false;
        if (rule == Release::join_hold) {
          release = join.release(cams[2], t);
        } else if (join.held && cams[2].initialized()) {  // the rule before JoinHold
          join.held = false;
          release = true;
        }
        if (release) cams[2].set_measurement(z[2]);
      }
      for (int i = 0; i < 5; ++i)
        if (!(down && i == 2) && cams[size_t(i)].initialized())
          send_estimate(cams[size_t(i)], net, t);
      for (int i = 0; i < 5; ++i) {
        if (down && i == 2) {
          net.receive(2, inbox);  // lost while down
          continue;
        }
        take_estimates(cams[size_t(i)], net, inbox);
        const bool step =
            k != kJoin || i != 2 || rule != Release::join_hold || join.may_step(cams[2], t);
        if (step) cams[size_t(i)].step(dt / N);
      }
    }
  }
  JoinMove m;
  for (int i : {0, 1, 3})
    m.move = std::max(m.move,
                      (cams[size_t(i)].estimate_world().translation() - before[size_t(i)]).norm());
  std::vector<SE3> nb;
  for (int i : {0, 1, 3}) nb.push_back(cams[size_t(i)].estimate_world());
  const double share = s.k_e / (s.k_e + s.k_s * 3);
  m.e = share * (p.g_wo[2].translation() - average_pose(nb).translation()).norm();
  return m;
}

}  // namespace

TEST(Exchange, ALateJoinerWhoseNeighboursStreamsStartApartMovesNoNeighbour) {
  const JoinMove prompt = join_move({}, Release::join_hold);
  std::printf(
      "every stream at once: neighbours' largest move in the join frame %.3f mm, e %.3f mm\n",
      prompt.move * 1e3, prompt.e * 1e3);
  EXPECT_LE(prompt.move, prompt.e);
  // Two of its three neighbours' streams late, each pair in turn. Let in by the rule before
  // JoinHold, camera 3 moves them further than e for some pair: the mechanism JoinHold
  // prevents, reproduced.
  double early = 0;
  for (const std::vector<int>& late : {std::vector<int>{0, 1}, {0, 3}, {1, 3}}) {
    const JoinMove m = join_move(late, Release::join_hold);
    const double e = join_move(late, Release::once_initialised).move;
    std::printf(
        "cameras %d and %d late: %.3f mm with JoinHold, %.3f mm by the rule before; e %.3f mm\n",
        late[0] + 1, late[1] + 1, m.move * 1e3, e * 1e3, m.e * 1e3);
    EXPECT_LE(m.move, m.e) << "cameras " << late[0] + 1 << " and " << late[1] + 1 << " late";
    early = std::max(early, e / m.e);
  }
  EXPECT_GT(early, 1.0);
}
