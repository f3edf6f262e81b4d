// The per-camera observer as the unit of the network: n of them joined by a transport defined
// here (a toy that delays every message by one round) reach the same averaging as the
// in-process NetworkedObserver, its messages are checked, and the error-model registry is the
// one table everything reads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <random>

#include "netvmo/observer/camera_observer.hpp"
#include "netvmo/observer/error_model.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"
#include "netvmo/observer/transport.hpp"
#include "paper5.hpp"

using namespace netvmo::obs;

namespace {

// The paper's Section 5 network: cameras 1..3 see their fictitious targets.
struct Paper5 : netvmo::test::Paper5 {
  Measurement z(int i) const {
    Measurement m;
    if (i < 3) {
      m.delta = true;
      m.g_io_true = g_wi[size_t(i)].inverse() * g_wo[size_t(i)];
    }
    return m;
  }
};

// A toy transport: every message reaches the sender's neighbours one round late.
class OneRoundLateTransport final : public Transport {
 public:
  explicit OneRoundLateTransport(Graph g) : graph_(std::move(g)), mail_(size_t(graph_.size())) {}
  void send(const EstimateMessage& m) override {
    for (int j : graph_.neighbors(m.sender)) mail_[size_t(j)].push_back({m, rounds_});
  }
  void receive(int receiver, std::vector<EstimateMessage>& out) override {
    out.clear();
    auto& box = mail_[size_t(receiver)];
    while (!box.empty() && box.front().second < rounds_) {
      out.push_back(box.front().first);
      box.pop_front();
    }
  }
  void next_round() { ++rounds_; }

 private:
  Graph graph_;
  std::vector<std::deque<std::pair<EstimateMessage, int>>> mail_;
  int rounds_ = 0;
};

std::vector<CameraObserver> make_cameras(const Paper5& p, const ObserverSettings& s) {
  std::vector<CameraObserver> cams;
  for (int i = 0; i < 5; ++i) {
    cams.emplace_back(i, p.graph.neighbors(i), s);
    cams.back().set_camera_pose(p.g_wi[size_t(i)]);
    cams.back().reset(make_pose({0, 0, 1}, Vec3::Zero()));
    cams.back().set_measurement(p.z(i));
  }
  return cams;
}

}  // namespace

TEST(CameraObserver, ComposedWithAToyTransportTheyAverageAsTheNetworkDoes) {
  Paper5 p;
  ObserverSettings s;  // exact error model, k_e = 1, k_s = 50
  auto cams = make_cameras(p, s);
  OneRoundLateTransport net(p.graph);
  const double h = 1.0 / 30.0 / 11.0;
  std::vector<EstimateMessage> inbox;
  for (int k = 0; k < 30 * 11 * 30; ++k) {  // 30 s
    for (auto& c : cams) net.send(c.publish(k * h));
    net.next_round();
    for (auto& c : cams) {
      net.receive(c.index(), inbox);
      for (const auto& m : inbox) EXPECT_EQ(c.receive(m), MessageVerdict::accepted);
    }
    for (auto& c : cams) c.step(h);
  }
  // The same network in process, for reference.
  NetworkedObserver ref(p.graph, s);
  ref.set_camera_poses(p.g_wi);
  ref.reset(std::vector<SE3>(5, make_pose({0, 0, 1}, Vec3::Zero())));
  std::vector<Measurement> z;
  for (int i = 0; i < 5; ++i) z.push_back(p.z(i));
  for (int k = 0; k < 30 * 30; ++k) ref.step(1.0 / 30.0, z);
  // A one-round delay of a stable linear consensus moves its equilibrium not at all: every
  // camera ends where the in-process network ends (to the integration's precision).
  for (int i = 0; i < 5; ++i) {
    const SE3 a = cams[size_t(i)].estimate_world(), b = ref.camera(i).estimate_world();
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-6) << "camera " << i + 1;
    EXPECT_LT(log_so3(a.linear().transpose() * b.linear()).norm(), 1e-6) << "camera " << i + 1;
  }
  // And blind cameras 4 and 5 sit at the average like the others.
  const SE3 g_star = average_pose(p.g_wo);
  for (int i : {3, 4})
    EXPECT_LT((cams[size_t(i)].estimate_world().translation() - g_star.translation()).norm(), 0.01);
}

TEST(CameraObserver, StepIsTheLieGroupEulerStepOfTheModel) {
  // One step equals exp(-h V^) g_bar exp(h u^) with u of (eq:input_f-), computed here by hand.
  ObserverSettings s;
  s.k_e = 2.0;
  s.k_s = 3.0;
  CameraObserver c(0, {1, 2}, s);
  const SE3 g_wi = make_pose({0.1, 0.2, 0.3}, {0.1, -0.2, 0.3});
  const SE3 g_bar = make_pose({0.0, 0.1, 1.5}, {2.9, 0.1, 0.2});
  const Vec6 V = (Vec6() << 0.1, 0.0, -0.2, 0.05, 0.0, 0.1).finished();
  c.set_camera_pose(g_wi);
  c.set_camera_velocity(V);
  c.reset(g_bar);
  Measurement z;
  z.delta = true;
  z.g_io_true = make_pose({0.05, 0.1, 1.6}, {2.95, 0.05, 0.25});
  c.set_measurement(z);
  EstimateMessage m1, m2;
  m1.sender = 1;
  m1.round = 1;
  m1.initialized = true;
  m1.g_w = make_pose({0.2, 0.3, 1.7}, {2.8, 0.2, 0.1});
  m2 = m1;
  m2.sender = 2;
  m2.g_w = make_pose({0.0, 0.4, 1.9}, {3.0, 0.0, 0.3});
  ASSERT_EQ(c.receive(m1), MessageVerdict::accepted);
  ASSERT_EQ(c.receive(m2), MessageVerdict::accepted);
  const double h = 0.01;
  c.step(h);
  const Vec6 u = 2.0 * E_R(g_bar.inverse() * *z.g_io_true) +
                 3.0 * (E_R(g_bar.inverse() * g_wi.inverse() * m1.g_w) +
                        E_R(g_bar.inverse() * g_wi.inverse() * m2.g_w));
  const SE3 expected = exp_se3(-h * V) * g_bar * exp_se3(h * u);
  EXPECT_LT((c.input() - u).norm(), 1e-12);
  EXPECT_LT((c.estimate().matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

// The step's arithmetic is written out on 3x3 rotations and translations for speed. The mutual
// term of one neighbour gives the bits of the plain Eigen expression; the summed mutual term, the
// exponential and the Euler step are cheaper but equivalent forms, which agree with the plain
// expressions to round-off: each side is a few rounded stages (at most ~10 operations each) of
// sums of products, each stage within a few eps of the magnitudes of its terms; the bounds below
// are 16 eps (32 for the whole step, twice the stages) times that scale. Measured with this seed:
// 1.4 (summed mutual term), 0.8 (exponential), 2.4 (step).
// References: the Isometry expressions, exp_so3 with the left Jacobian, Eigen's quaternion.
TEST(CameraObserver, StepArithmeticIsThePlainExpressionsToRoundOff) {
  std::mt19937 rng(12);  // fixed seed
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  const auto vec3 = [&](double scale) -> Vec3 { return Vec3(U(rng), U(rng), U(rng)) * scale; };
  const auto vec6 = [&](double scale) {
    Vec6 v;
    for (int c = 0; c < 6; ++c) v(c) = U(rng) * scale;
    return v;
  };
  const auto same = [](const auto& a, const auto& b) {  // bit for bit (0.0 and -0.0 differ)
    using Plain = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic>;
    const Plain x = a, y = b;
    return std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<size_t>(x.size())) == 0;
  };
  const double eps = std::numeric_limits<double>::epsilon();
  // Largest |difference| / (eps * scale) of each comparison.
  double mutual_sum_worst = 0.0, exp_worst = 0.0, step_worst = 0.0;
  int mutual_differs = 0;
  int branch[4] = {0, 0, 0, 0};  // the quaternion conversion's: trace > 0, else pivot 0, 1, 2
  for (int k = 0; k < 20000; ++k) {
    const double scale = k % 4 == 0 ? 1e-5 : 1.0;  // also the small-angle branches
    const SE3 a = make_pose(vec3(1.0), vec3(1.0)), b = make_pose(vec3(1.0), vec3(1.0));
    const Mat3 Rt = a.linear().transpose();
    Vec6 e;
    e.head<3>() = Rt * (b.translation() - a.translation());
    e.tail<3>() = e_R(Rt * b.linear());
    mutual_differs += !same(mutual_error(a, b), e);

    // The summed mutual term of 1..4 neighbours against the sum of the single terms.
    std::vector<SE3> nb{b};
    for (int m = 1; m < 1 + k % 4; ++m) nb.push_back(make_pose(vec3(1.0), vec3(1.0)));
    Vec6 sum = Vec6::Zero();
    double magnitude = static_cast<double>(nb.size()) * (1.0 + a.translation().norm());
    for (const auto& g : nb) {
      sum += mutual_error(a, g);
      magnitude += g.translation().norm();
    }
    mutual_sum_worst = std::max(
        mutual_sum_worst, (mutual_sum(a, nb) - sum).cwiseAbs().maxCoeff() / (eps * magnitude));

    Vec6 V = vec6(scale);
    for (int c = 0; c < 6; ++c)  // exact zeros in every pattern
      if ((k >> c) % 3 == 1) V(c) = (k >> c) % 2 ? 0.0 : -0.0;
    const Vec3 w = V.tail<3>();
    const double t2 = w.squaredNorm(), t = std::sqrt(t2);
    const double c1 = t < 1e-4 ? 0.5 - t2 / 24.0 : (1.0 - std::cos(t)) / t2;
    const double c2 = t < 1e-4 ? 1.0 / 6.0 - t2 / 120.0 : (t - std::sin(t)) / (t2 * t);
    const Mat3 W = hat(w);
    SE3 x = SE3::Identity();
    x.linear() = exp_so3(w);
    x.translation() = (Mat3::Identity() + c1 * W + c2 * W * W) * V.head<3>();
    const SE3 ex = exp_se3(V);
    const double exp_scale = (1.0 + t2) * (1.0 + V.head<3>().norm());
    exp_worst =
        std::max(exp_worst, (ex.matrix() - x.matrix()).cwiseAbs().maxCoeff() / (eps * exp_scale));

    const Vec6 u = vec6(1.0);
    const Vec6 Vw = k % 2 ? Vec6::Zero() : V;
    SE3 g = a * exp_se3(0.01 * u);
    if (!Vw.isZero(0.0)) g = exp_se3(-0.01 * Vw) * g;
    const Mat3& Rg = g.linear();
    int i = 0;
    if (Rg(1, 1) > Rg(0, 0)) i = 1;
    if (Rg(2, 2) > Rg(i, i)) i = 2;
    ++branch[Rg.trace() > 0.0 ? 0 : 1 + i];
    g.linear() = Eigen::Quaterniond(g.linear()).normalized().toRotationMatrix();
    step_worst = std::max(step_worst,
                          (integrate(a, Vw, u, 0.01).matrix() - g.matrix()).cwiseAbs().maxCoeff() /
                              (eps * (1.0 + g.translation().norm())));
  }
  EXPECT_EQ(mutual_differs, 0);
  EXPECT_LT(mutual_sum_worst, 16.0);
  EXPECT_LT(exp_worst, 16.0);
  EXPECT_LT(step_worst, 32.0);
  for (int c : branch) EXPECT_GT(c, 100);  // every branch of the conversion was compared
}

// The in-process fast path does not compute CameraObserver::receive's full check for a pose
// fresh from the Euler step published through a camera pose with room (kernel::check_has_room:
// |R_w^T R_w - I| <= 1e-7, det R_w > 0): the check accepts every such product. Camera poses at
// that bound, estimates of every kind of rotation.
TEST(CameraObserver, ACameraPoseWithRoomTimesAFreshEstimateIsAccepted) {
  std::mt19937 rng(5);  // fixed seed
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const auto vec3 = [&](double scale) -> Vec3 { return Vec3(U(rng), U(rng), U(rng)) * scale; };
  int refused = 0, near_bound = 0;
  for (int k = 0; k < 5000; ++k) {
    SE3 g_w = make_pose(vec3(3.0), vec3(3.0));
    // R_w (I + E), E symmetric: R_w^T R_w = I + 2E + E^2, entries up to 1e-7.
    Mat3 E;
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) E(r, c) = E(c, r) = 0.5e-7 * U(rng);
    g_w.linear() = g_w.linear() * (Mat3::Identity() + E);
    const Mat3 G = g_w.linear().transpose() * g_w.linear() - Mat3::Identity();
    if (G.cwiseAbs().maxCoeff() > 1e-7) continue;  // beyond the room the fast path allows
    near_bound += G.cwiseAbs().maxCoeff() > 0.5e-7;
    Vec6 u;
    u << vec3(1.0), vec3(3.0);
    const SE3 g_bar = integrate(make_pose(vec3(3.0), vec3(3.0)), Vec6::Zero(), u, 0.1);
    refused += check_pose(g_w * g_bar) != MessageVerdict::accepted;
  }
  EXPECT_EQ(refused, 0);
  EXPECT_GT(near_bound, 500);
}

TEST(CameraObserver, UninitialisedNeighboursAndCamerasTakeNoPart) {
  ObserverSettings s;
  CameraObserver c(0, {1}, s);
  const SE3 g0 = make_pose({0, 0, 1}, Vec3::Zero());
  c.reset(g0);
  EstimateMessage m;
  m.sender = 1;
  m.round = 1;
  m.initialized = false;  // the neighbour has no estimate yet
  m.g_w = make_pose({5, 5, 5}, Vec3::Zero());
  ASSERT_EQ(c.receive(m), MessageVerdict::accepted);
  c.step(0.01);
  EXPECT_TRUE(c.estimate().isApprox(g0));  // no measurement, no initialised neighbour
  m.round = 2;
  m.initialized = true;
  c.receive(m);
  c.set_initialized(false);
  c.step(0.01);
  EXPECT_TRUE(c.estimate().isApprox(g0));  // an uninitialised camera is frozen
  c.set_initialized(true);
  c.step(0.01);
  EXPECT_FALSE(c.estimate().isApprox(g0));
  c.forget(1);  // silent past a staleness bound: it leaves the mutual term
  const SE3 before = c.estimate();
  c.step(0.01);
  EXPECT_TRUE(c.estimate().isApprox(before));
}

TEST(CameraObserver, RefusesAndCountsBadMessages) {
  ObserverSettings s;
  CameraObserver c(0, {1, 2}, s);
  const SE3 g0 = make_pose({0, 0, 1}, Vec3::Zero());
  c.reset(g0);
  EstimateMessage good;
  good.sender = 1;
  good.round = 5;
  good.initialized = true;
  good.g_w = make_pose({0, 0, 1.1}, Vec3::Zero());

  auto bad = good;
  bad.sender = 7;
  EXPECT_EQ(c.receive(bad), MessageVerdict::not_a_neighbour);
  bad.sender = 0;  // itself
  EXPECT_EQ(c.receive(bad), MessageVerdict::not_a_neighbour);
  bad = good;
  bad.g_w.matrix()(0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(c.receive(bad), MessageVerdict::not_finite);
  bad = good;
  bad.g_w.linear() *= 1.01;  // not orthonormal
  EXPECT_EQ(c.receive(bad), MessageVerdict::not_a_rotation);
  bad = good;
  bad.g_w.linear() = -Mat3::Identity();  // orthonormal, but a reflection
  EXPECT_EQ(c.receive(bad), MessageVerdict::not_a_rotation);
  // None of them moved the estimate.
  c.step(0.01);
  EXPECT_TRUE(c.estimate().isApprox(g0));
  EXPECT_EQ(c.receive(good), MessageVerdict::accepted);
  auto older = good;
  older.round = 4;
  EXPECT_EQ(c.receive(older), MessageVerdict::out_of_order);
  const auto& r = c.refused();
  EXPECT_EQ(r[size_t(MessageVerdict::not_a_neighbour)], 2u);
  EXPECT_EQ(r[size_t(MessageVerdict::not_finite)], 1u);
  EXPECT_EQ(r[size_t(MessageVerdict::not_a_rotation)], 2u);
  EXPECT_EQ(r[size_t(MessageVerdict::out_of_order)], 1u);
  EXPECT_EQ(c.latest()[0]->round, 5u);
}

TEST(CameraObserver, RejectsBadSettingsAndNeighbourLists) {
  ObserverSettings s;
  EXPECT_THROW(CameraObserver(0, {0}, s), std::invalid_argument);
  EXPECT_THROW(CameraObserver(0, {1, 1}, s), std::invalid_argument);
  s.error_model = "nonsense";
  EXPECT_THROW(CameraObserver(0, {1}, s), std::invalid_argument);
  s = ObserverSettings{};
  s.k_s = -1;
  EXPECT_THROW(CameraObserver(0, {1}, s), std::invalid_argument);
}

TEST(ErrorModels, OneRegistryByName) {
  std::vector<std::string> names;
  for (const auto* m : error_models()) {
    names.emplace_back(m->name());
    EXPECT_EQ(&error_models().find(m->name()), m);
    EXPECT_FALSE(m->description().empty());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"exact", "jacobian", "pnp"}));
  EXPECT_EQ(error_models().names(), "exact, jacobian, pnp");
  try {
    error_models().find("jacobain");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exact, jacobian, pnp"), std::string::npos) << e.what();
  }
}

TEST(ErrorModels, EachReadsItsOwnMeasurementField) {
  const SE3 g_bar = make_pose({0, 0, 2}, {3.0, 0.1, 0.0});
  const SE3 g_true = make_pose({0.1, 0, 2.1}, {3.0, 0.15, 0.05});
  const SE3 g_pnp = make_pose({0.12, 0.01, 2.05}, {2.95, 0.1, 0.05});
  const FeatureModel fm = FeatureModel::square(0.2);
  Measurement z;
  z.delta = true;
  z.g_io_true = g_true;
  z.g_io_pnp = g_pnp;
  z.f = project(g_true, fm);
  EXPECT_LT(
      (error_models().find("exact").error(g_bar, z, fm) - E_R(g_bar.inverse() * g_true)).norm(),
      1e-15);
  EXPECT_LT((error_models().find("pnp").error(g_bar, z, fm) - E_R(g_bar.inverse() * g_pnp)).norm(),
            1e-15);
  EXPECT_LT(
      (error_models().find("jacobian").error(g_bar, z, fm) - reconstruct_error(g_bar, z.f, fm))
          .norm(),
      1e-15);
  // usable() needs delta and the model's own field.
  Measurement only_f;
  only_f.delta = true;
  only_f.f = z.f;
  EXPECT_TRUE(error_models().find("jacobian").usable(only_f));
  EXPECT_FALSE(error_models().find("pnp").usable(only_f));
  EXPECT_FALSE(error_models().find("exact").usable(only_f));
  z.delta = false;
  for (const auto* m : error_models()) EXPECT_FALSE(m->usable(z)) << m->name();
}

// The pose models (exact, pnp) compute E_R(g_bar^-1 g) on 3x3 rotations and translations
// (kernel::pose_error, also the in-process fast path's); the result must be the bits of the plain
// Isometry expression, for estimates near the measured pose (the usual case: small errors, many
// cancelling digits) and far from it. Their measured_pose() is the field they read.
TEST(ErrorModels, PoseModelsGiveTheBitsOfTheIsometryExpression) {
  std::mt19937 rng(21);  // fixed seed
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  const auto vec3 = [&](double scale) -> Vec3 { return Vec3(U(rng), U(rng), U(rng)) * scale; };
  const FeatureModel fm = FeatureModel::square(0.2);
  int differs = 0, compared = 0;
  for (int k = 0; k < 20000; ++k) {
    const double scale = k % 2 ? 1e-4 : 1.0;
    const SE3 g_bar = make_pose(vec3(1.0), vec3(1.0));
    const SE3 g = g_bar * make_pose(vec3(scale), vec3(scale));
    Measurement z;
    z.delta = true;
    (k % 3 ? z.g_io_true : z.g_io_pnp) = g;
    const ErrorModel& m = error_models().find(k % 3 ? "exact" : "pnp");
    ASSERT_EQ(m.measured_pose(z), k % 3 ? &*z.g_io_true : &*z.g_io_pnp);
    const Vec6 plain = E_R(g_bar.inverse(Eigen::Isometry) * g), e = m.error(g_bar, z, fm);
    differs += std::memcmp(plain.data(), e.data(), sizeof(double) * 6) != 0;
    ++compared;
  }
  EXPECT_EQ(differs, 0) << "of " << compared;
  Measurement none;
  none.delta = true;
  for (const auto* m : error_models()) EXPECT_EQ(m->measured_pose(none), nullptr) << m->name();
  none.g_io_true = none.g_io_pnp = SE3::Identity();
  none.f = Eigen::VectorXd::Zero(8);
  EXPECT_EQ(error_models().find("jacobian").measured_pose(none), nullptr);
}
