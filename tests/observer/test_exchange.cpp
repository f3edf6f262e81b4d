// The exchange round of exchange.hpp, written once: cameras run by hand with send_estimate /
// take_estimates / step (as a camera's own process runs them) reach bit for bit what the
// in-process NetworkedObserver reaches over a transport, and the staleness bound forgets exactly
// the neighbours older than it.
#include <gtest/gtest.h>

#include "netvmo/observer/exchange.hpp"
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
