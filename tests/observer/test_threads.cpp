// The observer's per-camera steps on several threads: results bit-identical to one thread and to
// the serial exchange through a Transport, for every estimator and error model; the worker
// pool's parts, grains and exceptions.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include "netvmo/observer/networked_observer.hpp"
#include "netvmo/observer/worker_pool.hpp"

using namespace netvmo::obs;

namespace {
// A ring with chords (degree 4) of n cameras on a circle around the target; every third one sees
// it, with a different (noisy) relative pose each, so that cameras do not move in lock step.
struct Network {
  Graph graph;
  std::vector<SE3> g_wi, g_bar;
  std::vector<Measurement> z;
};

Network network(int n, const FeatureModel& features) {
  std::vector<Graph::Edge> e;
  for (int i = 0; i < n; ++i) {
    e.emplace_back(i, (i + 1) % n);
    e.emplace_back(i, (i + n / 3) % n);
  }
  Network net{Graph(n, e), {}, {}, std::vector<Measurement>(static_cast<size_t>(n))};
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * 3.14159265358979 * i / n;
    net.g_wi.push_back(make_pose(Vec3(3 * std::cos(a), 3 * std::sin(a), 0), Vec3(0, 0, a)));
    net.g_bar.push_back(make_pose(Vec3(0.001 * (i % 11), 0, 2), Vec3(3.0, 0.001 * (i % 5), 0)));
    if (i % 3 == 0) {
      auto& zi = net.z[static_cast<size_t>(i)];
      zi.delta = true;
      zi.g_io_true = make_pose(Vec3(0.01 * (i % 7), 0.0, 2.0), Vec3(3.05, 0.02 * (i % 3), 0.0));
      zi.g_io_pnp = zi.g_io_true;
      zi.f = project(*zi.g_io_true, features);
    }
  }
  return net;
}

// Forwards to direct delivery, but is not an InProcessTransport: the observer then takes the
// serial exchange path through the Transport interface.
class Forwarding final : public Transport {
 public:
  explicit Forwarding(const Graph& g) : inner_(g) {}
  void send(const EstimateMessage& m) override { inner_.send(m); }
  void receive(int receiver, std::vector<EstimateMessage>& out) override {
    inner_.receive(receiver, out);
  }

 private:
  InProcessTransport inner_;
};

enum class Exchange { direct, in_process_transport, forwarding };

std::vector<SE3> run(const Network& net, ObserverSettings s, int threads, Exchange exchange,
                     int* used_threads = nullptr) {
  s.threads = threads;
  NetworkedObserver obs(net.graph, s);
  if (exchange == Exchange::in_process_transport)
    obs.set_transport(std::make_unique<InProcessTransport>(net.graph));
  if (exchange == Exchange::forwarding) obs.set_transport(std::make_unique<Forwarding>(net.graph));
  obs.set_camera_poses(net.g_wi);
  obs.reset(net.g_bar);
  for (int k = 0; k < 4; ++k) obs.step(1.0 / 30.0, net.z);
  if (used_threads) *used_threads = obs.threads();
  return obs.estimates_world();
}

// Two observers of the network: the in-process exchange (the fast path) and the serial exchange
// through a Transport that is not an InProcessTransport (per camera).
std::vector<NetworkedObserver> direct_and_forwarding(const Network& net,
                                                     const ObserverSettings& s) {
  std::vector<NetworkedObserver> obs;
  for (Exchange e : {Exchange::direct, Exchange::forwarding}) {
    obs.emplace_back(net.graph, s);
    if (e == Exchange::forwarding)
      obs.back().set_transport(std::make_unique<Forwarding>(net.graph));
    obs.back().set_camera_poses(net.g_wi);
    obs.back().reset(net.g_bar);
  }
  return obs;
}

void expect_bit_identical(const std::vector<SE3>& a, const std::vector<SE3>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size());
  size_t differing = 0;
  for (size_t i = 0; i < a.size(); ++i)
    differing += !(a[i].matrix().array() == b[i].matrix().array()).all();
  EXPECT_EQ(differing, 0u) << what;
}
}  // namespace

TEST(Threads, ResultsAreBitIdenticalForAnyThreadCountAndExchange) {
  const int n = 3 * kCamerasPerThread;  // enough cameras for three threads
  for (const char* estimator : {"vmo", "zero-offset"})
    for (const char* model : {"exact", "jacobian", "pnp"}) {
      ObserverSettings s;
      s.estimator = estimator;
      s.error_model = model;
      if (error_models().find(model).input() == MeasurementInput::features &&
          std::string(estimator) == "zero-offset")
        continue;  // zero-offset averages poses
      SCOPED_TRACE(std::string(estimator) + " / " + model);
      const Network net = network(n, s.features);
      int used = 0;
      const auto one = run(net, s, 1, Exchange::direct, &used);
      EXPECT_EQ(used, 1);
      // The estimates moved: the comparison below is not between initial values.
      EXPECT_GT((one[0].translation() - (net.g_wi[0] * net.g_bar[0]).translation()).norm(), 1e-3);
      for (int threads : {2, 3}) {
        expect_bit_identical(one, run(net, s, threads, Exchange::direct, &used), "direct");
        EXPECT_EQ(used, threads);
        expect_bit_identical(one, run(net, s, threads, Exchange::in_process_transport),
                             "InProcessTransport");
      }
      // The serial exchange through the Transport interface, one and two threads.
      expect_bit_identical(one, run(net, s, 1, Exchange::forwarding), "forwarding, 1 thread");
      expect_bit_identical(one, run(net, s, 2, Exchange::forwarding), "forwarding, 2 threads");
    }
}

// The in-process exchange of the vmo runs on compact arrays and writes the cameras' state back
// after each frame; it must leave every camera exactly as the per-camera exchange through a
// Transport does: estimate, input, round, every stored neighbour message and the refusal counts.
// Also when messages are refused (a believed pose that is not a rotation from the start; an
// estimate that diverges to infinity in the middle of a frame), when cameras start from their
// neighbours, when camera poses are rotations only up to round-off (the fast path's cheaper
// check of a published pose, kernel::check_has_room), and when after two frames a camera starts
// moving or its believed pose stops being a rotation (the next frames run camera by camera on the
// neighbour messages the fast path deferred, CameraObserver::NeighbourMessages; the bad camera's
// neighbours keep using its last accepted one). Half the cameras are compared through a copy
// (which writes the deferred messages first).
TEST(Threads, InProcessFastPathLeavesEveryCameraAsTheTransportExchangeDoes) {
  const int n = 2 * kCamerasPerThread;  // two threads
  enum class Case {
    plain,
    bad_camera_pose,
    divergence,
    start_from_neighbours,
    camera_round_off,
    starts_moving,
    bad_camera_pose_later
  };
  for (Case c : {Case::plain, Case::bad_camera_pose, Case::divergence, Case::start_from_neighbours,
                 Case::camera_round_off, Case::starts_moving, Case::bad_camera_pose_later}) {
    SCOPED_TRACE(static_cast<int>(c));
    ObserverSettings s;
    s.threads = 2;
    Network net = network(n, s.features);
    if (c == Case::bad_camera_pose) net.g_wi[7].linear() *= 1.5;  // refused by its neighbours
    if (c == Case::camera_round_off)  // R^T R - I of 0.9e-7 (within the fast path's room for a
      // finiteness test), 3e-7 and 0.99e-6 (beyond it: the full check, which still accepts)
      for (auto [i, e] : {std::pair{3, 0.45e-7}, std::pair{4, 1.5e-7}, std::pair{5, 0.495e-6}})
        net.g_wi[static_cast<size_t>(i)].linear() *= 1.0 + e;
    if (c == Case::divergence) {  // far beyond the stable step: overflows within 20 frames
      s.k_s = 1e12;
      s.substeps = 3;
    }
    if (c == Case::start_from_neighbours) s.init_from_neighbours = true;
    std::vector<NetworkedObserver> obs = direct_and_forwarding(net, s);
    if (c == Case::start_from_neighbours) {
      std::vector<bool> active(static_cast<size_t>(n), true);
      for (int i = 0; i < n; i += 5) active[static_cast<size_t>(i)] = false;
      for (auto& o : obs) o.set_active(active);
    }
    const int frames = c == Case::divergence ? 20 : 4;
    for (int frame = 0; frame < frames; ++frame) {
      if (c == Case::starts_moving && frame == 2) {
        std::vector<Vec6> V(static_cast<size_t>(n), Vec6::Zero());
        V[3] << 0.01, 0.0, 0.0, 0.0, 0.0, 0.02;
        for (auto& o : obs) o.set_camera_velocities(V);
      }
      if (c == Case::bad_camera_pose_later && frame == 2) {
        auto g_wi = net.g_wi;
        g_wi[7].linear() *= 1.5;
        for (auto& o : obs) o.set_camera_poses(g_wi);
      }
      for (auto& o : obs) o.step(1.0 / 30.0, net.z);
      // (Frame 2 of these cases starts with the messages still deferred: nobody looks at frame 1.)
      if ((c == Case::starts_moving || c == Case::bad_camera_pose_later) && frame == 1) continue;
      size_t differing = 0, refused = 0;
      for (int i = 0; i < n; ++i) {
        const CameraObserver copy = std::as_const(obs[0]).camera(i);
        const CameraObserver &a = i % 2 ? copy : std::as_const(obs[0]).camera(i),
                             &b = std::as_const(obs[1]).camera(i);
        const auto same = [](const auto& x, const auto& y) {
          return ((x.array() == y.array()) || (x.array().isNaN() && y.array().isNaN())).all();
        };
        bool ok = same(a.estimate().matrix(), b.estimate().matrix()) &&
                  same(a.input(), b.input()) && a.initialized() == b.initialized() &&
                  a.refused() == b.refused();
        for (size_t k = 0; ok && k < a.latest().size(); ++k) {
          const auto &x = a.latest()[k], &y = b.latest()[k];
          ok = x.has_value() == y.has_value() &&
               (!x || (x->sender == y->sender && x->round == y->round &&
                       x->initialized == y->initialized && x->stamp == y->stamp &&
                       same(x->g_w.matrix(), y->g_w.matrix())));
        }
        differing += !ok;
        for (auto r : a.refused()) refused += r;
      }
      EXPECT_EQ(differing, 0u) << "frame " << frame;
      if (c == Case::bad_camera_pose || (c == Case::divergence && frame == frames - 1) ||
          (c == Case::bad_camera_pose_later && frame >= 2)) {
        EXPECT_GT(refused, 0u) << "frame " << frame;
      }
      if (c == Case::plain || c == Case::camera_round_off || c == Case::starts_moving) {
        EXPECT_EQ(refused, 0u);
      }
    }
  }
}

// After a frame of the fast path the cameras' neighbour messages are written when first read
// (CameraObserver::NeighbourMessages): two threads reading every camera's at once get the same
// messages, those the per-camera exchange through a Transport stores.
TEST(Threads, DeferredNeighbourMessagesReadFromTwoThreadsAtOnce) {
  const int n = 2 * kCamerasPerThread;
  ObserverSettings s;
  s.threads = 2;
  const Network net = network(n, s.features);
  std::vector<NetworkedObserver> obs = direct_and_forwarding(net, s);
  using Slots = std::vector<std::optional<EstimateMessage>>;
  const auto rounds_and_poses = [](const Slots& m) {
    std::vector<double> v;
    for (const auto& x : m) {
      v.push_back(x ? static_cast<double>(x->round) : -1.0);
      if (x) v.insert(v.end(), x->g_w.data(), x->g_w.data() + 16);
    }
    return v;
  };
  for (int frame = 0; frame < 3; ++frame) {
    for (auto& o : obs) o.step(1.0 / 30.0, net.z);
    std::vector<std::vector<double>> seen[2];
    std::atomic<int> ready{0};
    const NetworkedObserver& fast = obs[0];
    const auto read_all = [&](int t) {
      ++ready;
      while (ready.load() < 2) std::this_thread::yield();  // start together
      for (int i = 0; i < n; ++i) seen[t].push_back(rounds_and_poses(fast.camera(i).latest()));
    };
    std::thread other(read_all, 1);
    read_all(0);
    other.join();
    size_t differing = 0;
    for (int i = 0; i < n; ++i) {
      const auto expected = rounds_and_poses(std::as_const(obs[1]).camera(i).latest());
      differing += seen[0][static_cast<size_t>(i)] != expected;
      differing += seen[1][static_cast<size_t>(i)] != expected;
    }
    EXPECT_EQ(differing, 0u) << "frame " << frame;
  }
}

TEST(Threads, SmallNetworksStayOnTheCallingThread) {
  ObserverSettings s;
  s.threads = 8;
  const Network net = network(2 * kCamerasPerThread - 1, s.features);
  EXPECT_EQ(NetworkedObserver(net.graph, s).threads(), 1);
  s.threads = -1;
  EXPECT_THROW(NetworkedObserver(net.graph, s), std::invalid_argument);
}

TEST(WorkerPool, EveryIndexOnceAndTheSmallestIndexExceptionWins) {
  WorkerPool pool(3);
  ASSERT_EQ(pool.size(), 3);
  std::vector<std::atomic<int>> hits(1000);
  pool.for_each(1000, 3, [&](int i) { ++hits[static_cast<size_t>(i)]; });
  for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
  // Indices 100 (part 0) and 900 (part 2) throw: the first one is reported.
  try {
    pool.for_each(1000, 3, [](int i) {
      if (i == 100 || i == 900) throw std::runtime_error(std::to_string(i));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "100");
  }
  // The pool still works after an exception.
  std::atomic<int> sum{0};
  pool.for_each(10, 2, [&](int i) { sum += i; });
  EXPECT_EQ(sum.load(), 45);
}

// A thread through with its own part takes the grains of another part that its thread has not
// reached. The first index of part 0 to run waits until another thread has run an index of part
// 0: with every part on its own thread nobody else ever does, and the wait runs out (bounded, so
// that a loaded machine, which may keep the worker off the CPU for a while, still passes).
TEST(WorkerPool, AThreadThroughWithItsPartTakesWhatIsLeftOfAnother) {
  WorkerPool pool(2);
  constexpr int kCount = 2000;  // part 0 is [0, 1000), part 1 [1000, 2000)
  std::vector<std::thread::id> ran(kCount);
  std::atomic<std::thread::id> first{};
  std::atomic<int> taken{0};
  bool waited_in_vain = false;
  pool.for_each(kCount, 2, [&](int i) {
    const auto me = std::this_thread::get_id();
    ran[static_cast<size_t>(i)] = me;
    if (i >= kCount / 2) return;
    auto none = std::thread::id();
    if (first.compare_exchange_strong(none, me)) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
      while (taken.load() == 0 && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      waited_in_vain = taken.load() == 0;
    } else if (first.load() != me) {
      ++taken;
    }
  });
  EXPECT_FALSE(waited_in_vain) << "no other thread ran an index of part 0 within 60 s";
  EXPECT_GT(taken.load(), 0);
  for (const auto& id : ran) ASSERT_NE(id, std::thread::id()) << "an index did not run";
}

// A waiting thread polls for the pool's spin and then sleeps on a condition variable; both ways
// must hand over every job. With no spin every wait sleeps; with a long one every wait polls; with
// a short one and pauses between jobs longer than it, the workers are asleep when the next job
// comes.
TEST(WorkerPool, JobsReachPollingAndSleepingWorkers) {
  using std::chrono::microseconds;
  for (const auto spin : {microseconds(0), microseconds(100000), microseconds(50)}) {
    WorkerPool pool(3, spin);
    std::vector<int> count(64, 0);
    for (int job = 0; job < 200; ++job) {
      // 1, 2 and 3 parts in turn: workers left out of a job still keep in step.
      pool.for_each(64, 1 + job % 3, [&](int i) { ++count[static_cast<size_t>(i)]; });
      if (spin == microseconds(50) && job % 20 == 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    for (int c : count) ASSERT_EQ(c, 200) << "spin " << spin.count() << " us";
  }
}
