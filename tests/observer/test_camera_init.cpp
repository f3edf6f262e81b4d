// Self-initialisation of the per-camera observer (the same in process and in a camera's own
// process) and the incarnation of its messages.
#include <gtest/gtest.h>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"

using namespace netvmo::obs;

namespace {
ObserverSettings self_init(const std::string& model = "pnp") {
  ObserverSettings s;
  s.error_model = model;
  s.init_from_measurement = true;
  s.init_from_neighbours = true;
  return s;
}

Measurement seen(const SE3& g_io) {
  Measurement z;
  z.delta = true;
  z.g_io_pnp = g_io;
  z.f = Eigen::Matrix<double, 8, 1>::Zero();
  return z;
}
}  // namespace

TEST(CameraInit, ASeeingCameraStartsFromItsPnpPose) {
  CameraObserver c(0, {1}, self_init());
  c.set_initialized(false);
  c.set_measurement(Measurement{});  // blind: nothing happens
  EXPECT_FALSE(c.initialized());
  const SE3 g = make_pose({0.1, -0.2, 1.5}, {0.1, 0.2, 0.3});
  c.set_measurement(seen(g));
  EXPECT_TRUE(c.initialized());
  EXPECT_TRUE(c.estimate().isApprox(g, 0.0));
  // Once initialised, a later PnP pose does not reset a (pnp model) estimate.
  c.set_measurement(seen(make_pose({0, 0, 2}, {0, 0, 0})));
  EXPECT_TRUE(c.estimate().isApprox(g, 0.0));
}

TEST(CameraInit, TheFeatureModelIsRescuedWhenTheTagCrossesTheCameraPlane) {
  CameraObserver c(0, {}, self_init("jacobian"));
  c.reset(make_pose({0, 0, 0.01}, {0, 0, 0}));  // corners at depth 0.01 < 0.05
  const SE3 g = make_pose({0, 0, 1.2}, {0.0, 0.1, 0.0});
  c.set_measurement(seen(g));
  EXPECT_TRUE(c.estimate().isApprox(g, 0.0));
}

TEST(CameraInit, ABlindCameraStartsFromItsInitialisedNeighboursAverage) {
  CameraObserver c(2, {0, 1, 3}, self_init());
  c.set_initialized(false);
  const SE3 g_w2 = make_pose({1, 0, 0}, {0, 0, 0.5});
  c.set_camera_pose(g_w2);
  EstimateMessage a, b, blind;
  a.sender = 0, b.sender = 1, blind.sender = 3;
  a.round = b.round = blind.round = 1;
  a.initialized = b.initialized = true;  // blind.initialized = false: left out
  a.g_w = make_pose({0, 0, 1}, {0.1, 0, 0});
  b.g_w = make_pose({0, 0.2, 1}, {0, 0.1, 0});
  blind.g_w = make_pose({5, 5, 5}, {0, 0, 0});
  c.receive(a);
  c.receive(b);
  c.receive(blind);
  c.step(0.0);  // initialises first, then steps by nothing
  ASSERT_TRUE(c.initialized());
  EXPECT_TRUE(c.estimate_world().isApprox(average_pose({a.g_w, b.g_w}), 1e-12));
}

TEST(CameraInit, WithoutNeighbourInitialisationABlindCameraWaits) {
  auto s = self_init();
  s.init_from_neighbours = false;
  CameraObserver c(1, {0}, s);
  c.set_initialized(false);
  EstimateMessage a;
  a.sender = 0;
  a.round = 1;
  a.initialized = true;
  c.receive(a);
  c.step(0.01);
  EXPECT_FALSE(c.initialized());
}

TEST(CameraInit, InitialisationSpreadsOneHopPerRound) {
  // A path 0 - 1 - 2 - 3; only camera 0 sees the target.
  std::vector<Measurement> z(4);
  z[0] = seen(make_pose({0, 0, 1}, {0, 0, 0}));
  ObserverSettings one = self_init();
  one.substeps = 1;
  NetworkedObserver step1(Graph(4, {{0, 1}, {1, 2}, {2, 3}}), one);
  step1.set_active({false, false, false, false});
  const std::vector<std::vector<bool>> expected = {
      {true, true, false, false}, {true, true, true, false}, {true, true, true, true}};
  for (const auto& e : expected) {
    step1.step(1.0 / 330, z);  // one round
    EXPECT_EQ(step1.active(), e);
  }
}

TEST(CameraInit, ARestartedSenderIsHeardAgain) {
  CameraObserver c(0, {1}, ObserverSettings{});
  EstimateMessage m;
  m.sender = 1;
  m.initialized = true;
  m.incarnation = 5;
  m.round = 40;
  EXPECT_EQ(c.receive(m), MessageVerdict::accepted);
  m.round = 3;  // same incarnation, older round
  EXPECT_EQ(c.receive(m), MessageVerdict::out_of_order);
  m.incarnation = 6;  // restarted: counts from round 1 again
  m.round = 1;
  EXPECT_EQ(c.receive(m), MessageVerdict::accepted);
  m.incarnation = 5;  // a late message of the previous incarnation
  m.round = 41;
  EXPECT_EQ(c.receive(m), MessageVerdict::out_of_order);
  CameraObserver sender(1, {0}, ObserverSettings{});
  sender.set_incarnation(9);
  EXPECT_EQ(sender.publish().incarnation, 9u);
}
