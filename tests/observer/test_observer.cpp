// The networked observer's dynamics: steady state against the independent linear solution,
// stability of the sub-stepping, the camera-motion term and the connectivity check.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"
#include "paper5.hpp"

using namespace netvmo::obs;

namespace {
struct PaperSetup : netvmo::test::Paper5 {
  std::vector<Measurement> measurements() const {
    std::vector<Measurement> z(5);
    for (int i = 0; i < 3; ++i) {
      z[static_cast<size_t>(i)].delta = true;
      z[static_cast<size_t>(i)].g_io_true =
          g_wi[static_cast<size_t>(i)].inverse() * g_wo[static_cast<size_t>(i)];
    }
    return z;
  }
};

NetworkedObserver run_paper(double k_s, double seconds) {
  PaperSetup s;
  ObserverSettings set;
  set.k_e = 1.0;
  set.k_s = k_s;
  NetworkedObserver obs(s.graph, set);
  obs.set_camera_poses(s.g_wi);
  obs.reset(std::vector<SE3>(5, make_pose({0, 0, 1}, Vec3::Zero())));
  const auto z = s.measurements();
  for (int k = 0; k < static_cast<int>(seconds * 30); ++k) obs.step(1.0 / 30.0, z);
  return obs;
}
}  // namespace

TEST(Observer, SteadyStatePositionsSolveTheLinearEquation) {
  PaperSetup s;
  const Eigen::MatrixXd L = Eigen::MatrixXd(s.graph.laplacian());
  Eigen::MatrixXd Delta = Eigen::MatrixXd::Zero(5, 5);
  Eigen::MatrixXd Po = Eigen::MatrixXd::Zero(5, 3);
  for (int i = 0; i < 3; ++i) {
    Delta(i, i) = 1.0;
    Po.row(i) = s.g_wo[static_cast<size_t>(i)].translation().transpose();
  }
  for (double k_s : {1.0, 50.0}) {
    // (k_e Delta + k_s L) p = k_e Delta p_o, solved independently of the observer.
    const Eigen::MatrixXd P = (Delta + k_s * L).fullPivLu().solve(Delta * Po);
    const auto obs = run_paper(k_s, 60.0);
    const auto est = obs.estimates_world();
    for (int i = 0; i < 5; ++i)
      EXPECT_LT((est[static_cast<size_t>(i)].translation() - P.row(i).transpose()).norm(), 1e-6)
          << "k_s=" << k_s << " camera " << i + 1;
  }
}

TEST(Observer, LargerMutualGainAveragesBetter) {
  PaperSetup s;
  const SE3 g_star = average_pose(s.g_wo);
  const Energies e1 = energies(run_paper(1.0, 30.0).estimates_world(), g_star);
  const Energies e50 = energies(run_paper(50.0, 30.0).estimates_world(), g_star);
  EXPECT_LT(e50.U_p, e1.U_p);
  EXPECT_LT(e50.U_R, e1.U_R);
  // Theorem 1: an orientation offset remains for small k.
  EXPECT_GT(e50.U_R, 1e-6);
}

TEST(Observer, SubstepsFollowTheStabilityBound) {
  ObserverSettings s;
  s.k_e = 1.0;
  s.k_s = 50.0;
  EXPECT_EQ(stable_substeps(1.0 / 30.0, s, 3), 11);  // ceil(301 / 30)
  s.k_s = 1.0;
  EXPECT_EQ(stable_substeps(1.0 / 30.0, s, 3), 1);
  // The bound matters: a single explicit step per frame at k_s = 50 diverges.
  PaperSetup p;
  ObserverSettings one;
  one.k_s = 50.0;
  one.substeps = 1;
  NetworkedObserver obs(p.graph, one);
  obs.set_camera_poses(p.g_wi);
  obs.reset(std::vector<SE3>(5, make_pose({0, 0, 1}, Vec3::Zero())));
  const auto z = p.measurements();
  for (int k = 0; k < 30; ++k) obs.step(1.0 / 30.0, z);
  double spread = 0.0;
  for (const auto& g : obs.estimates_world()) spread = std::max(spread, g.translation().norm());
  EXPECT_GT(spread, 100.0);
}

TEST(Observer, SingleVisualMotionObserverConvergesToTheMeasuredPose) {
  // k_s = 0 on a graph of one camera: the visual motion observer of (TCST07).
  ObserverSettings s;
  s.k_s = 0.0;
  s.k_e = 2.0;
  NetworkedObserver obs(Graph(1, {}), s);
  const SE3 g_io = make_pose({0.2, -0.1, 2.0}, {2.8, 0.2, 0.1});
  obs.reset({make_pose({0, 0, 1}, {3.0, 0.0, 0.0})});
  Measurement z;
  z.delta = true;
  z.g_io_true = g_io;
  for (int k = 0; k < 300; ++k) obs.step(1.0 / 30.0, {z});
  EXPECT_LT(E_R(obs.estimates()[0].inverse() * g_io).norm(), 1e-6);
}

TEST(Observer, FeatureErrorModelConvergesToTheMeasuredPose) {
  ObserverSettings s;
  s.k_s = 0.0;
  s.error_model = "jacobian";
  s.features = FeatureModel::square(0.2);
  NetworkedObserver obs(Graph(1, {}), s);
  const SE3 g_io = make_pose({0.2, -0.1, 2.0}, {2.9, 0.2, 0.1});
  obs.reset({make_pose({0, 0, 1.5}, {3.0, 0.0, 0.0})});
  Measurement z;
  z.delta = true;
  z.f = project(g_io, s.features);
  for (int k = 0; k < 600; ++k) obs.step(1.0 / 30.0, {z});
  EXPECT_LT(E_R(obs.estimates()[0].inverse() * g_io).norm(), 1e-5);
}

TEST(Observer, CameraMotionTermTracksAStaticTargetFromAMovingCamera) {
  // A camera moving with constant body velocity V sees g_io(t) = exp(-V t) g_io(0). With the
  // -hat(V) g_bar term the estimate stays locked on; without it, it lags.
  const Vec6 V = (Vec6() << 0.3, 0.0, 0.1, 0.0, 0.2, 0.05).finished();
  const SE3 g_io0 = make_pose({0.1, 0.0, 2.0}, {3.0, 0.1, 0.0});
  double err_with = 0.0, err_without = 0.0;
  for (bool with_term : {true, false}) {
    ObserverSettings s;
    s.k_s = 0.0;
    s.k_e = 1.0;
    NetworkedObserver obs(Graph(1, {}), s);
    obs.reset({g_io0});
    if (with_term) obs.set_camera_velocities({V});
    Measurement z;
    z.delta = true;
    double err = 0.0;
    for (int k = 1; k <= 60; ++k) {
      // The image taken at the start of the frame drives the step to its end.
      z.g_io_true = exp_se3(-(k - 1) / 30.0 * V) * g_io0;
      obs.step(1.0 / 30.0, {z});
      const double t = k / 30.0;
      err = std::max(err, E_R(obs.estimates()[0].inverse() * exp_se3(-t * V) * g_io0).norm());
    }
    (with_term ? err_with : err_without) = err;
  }
  EXPECT_LT(err_with, 0.02 * err_without);
  EXPECT_GT(err_without, 0.05);
}

TEST(Observer, BelievedPoseMovesWithTheCameraVelocityOverTheSubSteps) {
  // The believed pose follows V over the frame's sub-steps and lands on g_wi exp(dt V); an
  // estimate without input (blind, alone) then stays put in the world while its camera moves.
  const Vec6 V = (Vec6() << 0.3, -0.1, 0.2, 0.05, 0.2, -0.1).finished();
  const SE3 g_wi = make_pose({1.0, -2.0, 1.5}, {1.2, -0.3, 0.4});
  ObserverSettings s;
  s.k_s = 0.0;
  s.substeps = 7;
  NetworkedObserver obs(Graph(1, {}), s);
  obs.reset({make_pose({0.1, 0.0, 2.0}, {3.0, 0.1, 0.0})});
  obs.set_camera_poses({g_wi});
  obs.set_camera_velocities({V});
  const SE3 before = obs.estimates_world()[0], local_before = obs.estimates()[0];
  obs.step(0.1, {Measurement{}});
  EXPECT_TRUE(obs.camera(0).camera_pose().isApprox(g_wi * exp_se3(0.1 * V), 1e-12));
  EXPECT_TRUE(obs.estimates_world()[0].isApprox(before, 1e-12));
  EXPECT_FALSE(obs.estimates()[0].isApprox(local_before, 1e-3));  // in its camera's frame it moved
}

TEST(Observer, BlindCamerasFollowTheirNeighbours) {
  const auto obs = run_paper(50.0, 30.0);
  const auto est = obs.estimates_world();
  // Cameras 4 and 5 never see the target, yet end near the visible cameras' estimates.
  for (int i : {3, 4})
    EXPECT_LT((est[static_cast<size_t>(i)].translation() - est[0].translation()).norm(), 0.01);
}

TEST(Observer, RefusesADisconnectedGraph) {
  try {
    NetworkedObserver obs(Graph(4, {{0, 1}, {2, 3}}), ObserverSettings{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("{0,1} {2,3}"), std::string::npos) << e.what();
  }
}

TEST(Observer, MutualErrorEqualsTheDefinition) {
  // E_R(g_bar_i^-1 g_ij g_bar_j) with g_ij = g_wi^-1 g_wj (eq:input_f-)
  const SE3 g_wi = make_pose({1, 2, 3}, {0.1, 0.2, 0.3});
  const SE3 g_wj = make_pose({-1, 0, 2}, {-0.3, 0.1, 2.0});
  const SE3 gbi = make_pose({0.1, 0.2, 1.5}, {0.5, 0.1, 0.0});
  const SE3 gbj = make_pose({0.3, -0.2, 2.5}, {0.0, 1.1, 0.2});
  const Vec6 ref = E_R(gbi.inverse() * (g_wi.inverse() * g_wj) * gbj);
  EXPECT_LT((mutual_error(g_wi * gbi, g_wj * gbj) - ref).norm(), 1e-13);
}

namespace {
// Delivers every message except those from one camera, which its neighbours never hear.
class DroppingTransport final : public Transport {
 public:
  DroppingTransport(Graph g, int silent, int* receive_calls)
      : inner_(std::move(g)), silent_(silent), calls_(receive_calls) {}
  void send(const EstimateMessage& m) override {
    if (m.sender != silent_) inner_.send(m);
  }
  void receive(int receiver, std::vector<EstimateMessage>& out) override {
    ++*calls_;
    inner_.receive(receiver, out);
  }

 private:
  InProcessTransport inner_;
  int silent_;
  int* calls_;
};
}  // namespace

TEST(Observer, ExchangesGoThroughTheTransportOncePerSubstep) {
  PaperSetup p;
  ObserverSettings s;
  NetworkedObserver a(p.graph, s), b(p.graph, s);
  int calls = 0;
  b.set_transport(std::make_unique<DroppingTransport>(p.graph, /*silent=*/4, &calls));
  for (auto* o : {&a, &b}) {
    o->set_camera_poses(p.g_wi);
    o->reset(std::vector<SE3>(5, make_pose({0, 0, 1}, Vec3::Zero())));
  }
  const auto z = p.measurements();
  for (int k = 0; k < 30; ++k) {
    a.step(1.0 / 30.0, z);
    b.step(1.0 / 30.0, z);
  }
  EXPECT_EQ(calls, 5 * 30 * a.substeps(1.0 / 30.0));  // every camera, every round
  // Camera 5's neighbours (1 and 4) never hear from it, so the runs differ.
  EXPECT_GT((a.estimates_world()[0].translation() - b.estimates_world()[0].translation()).norm(),
            1e-3);
}

TEST(Observer, InactiveCamerasAreFrozenAndIgnored) {
  PaperSetup p;
  NetworkedObserver obs(p.graph, ObserverSettings{});
  obs.set_camera_poses(p.g_wi);
  // Camera 5 starts at an absurd estimate but is inactive: nobody is pulled towards it.
  std::vector<SE3> init(5, make_pose({0, 0, 1}, Vec3::Zero()));
  init[4] = make_pose({100, 100, 100}, Vec3(1, 2, 0.5));
  obs.reset(init);
  obs.set_active({true, true, true, true, false});
  const auto z = p.measurements();
  for (int k = 0; k < 600; ++k) obs.step(1.0 / 30.0, z);
  EXPECT_TRUE(obs.estimates()[4].isApprox(init[4]));
  const SE3 g_star = average_pose(p.g_wo);
  for (int i = 0; i < 4; ++i)
    EXPECT_LT(
        (obs.estimates_world()[static_cast<size_t>(i)].translation() - g_star.translation()).norm(),
        0.05);
}
