// DdsTransport between processes: lock-step exchange, and a rogue participant on the topic.
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include <dds/dds.h>

#include "../net/dds_peer_setup.hpp"
#include "NetvmoEstimate.h"
#include "net_test_util.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "test_util.hpp"

using namespace netvmo;

namespace {

constexpr int kRounds = 40;

struct PeerLog {
  std::vector<std::pair<int, std::uint64_t>> accepted;  // (sender, round)
  std::vector<obs::SE3> poses;                          // accepted poses
  obs::SE3 final_estimate = obs::SE3::Identity();
  std::vector<unsigned long long> refused;
  unsigned long long sent = 0, received = 0, late = 0, foreign = 0;
};

obs::SE3 read_pose(std::istringstream& in) {
  obs::SE3 g = obs::SE3::Identity();
  for (int r = 0; r < 3; ++r) in >> g.translation()(r);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) in >> g.linear()(r, c);
  return g;
}

PeerLog read_log(const std::filesystem::path& f) {
  PeerLog log;
  std::ifstream in(f);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string head;
    s >> head;
    if (head == "final") {
      log.final_estimate = read_pose(s);
    } else if (head == "refused") {
      unsigned long long n;
      while (s >> n) log.refused.push_back(n);
    } else if (head == "stats") {
      s >> log.sent >> log.received >> log.late >> log.foreign;
    } else {
      std::uint64_t round;
      s >> round;
      log.accepted.emplace_back(std::stoi(head), round);
      log.poses.push_back(read_pose(s));
    }
  }
  return log;
}

// The same two cameras exchanging in process: the messages each one publishes, by round, and
// the final estimates.
struct Reference {
  std::vector<std::vector<obs::SE3>> published{2};
  std::vector<obs::SE3> final_estimate;
};

Reference reference() {
  std::vector<obs::CameraObserver> cam;
  cam.emplace_back(0, std::vector<int>{1}, net_test::peer_settings());
  cam.emplace_back(1, std::vector<int>{0}, net_test::peer_settings());
  for (auto& c : cam) net_test::setup_peer(c);
  Reference ref;
  for (int k = 0; k < kRounds; ++k) {
    const auto m0 = cam[0].publish(k * net_test::kH), m1 = cam[1].publish(k * net_test::kH);
    ref.published[0].push_back(m0.g_w);
    ref.published[1].push_back(m1.g_w);
    cam[0].receive(m1);
    cam[1].receive(m0);
    for (auto& c : cam) c.step(net_test::kH);
  }
  for (auto& c : cam) ref.final_estimate.push_back(c.estimate());
  return ref;
}

void expect_exactly_the_other(const PeerLog& log, int other, const Reference& ref) {
  ASSERT_EQ(log.accepted.size(), static_cast<size_t>(kRounds));
  for (int k = 0; k < kRounds; ++k) {
    EXPECT_EQ(log.accepted[k].first, other);
    EXPECT_EQ(log.accepted[k].second, static_cast<std::uint64_t>(k + 1));
    EXPECT_LE((log.poses[k].matrix() - ref.published[other][k].matrix()).cwiseAbs().maxCoeff(), 0.0)
        << "round " << k + 1;
  }
}

std::vector<std::string> peer_cmd(int domain, int self, int writers,
                                  const std::filesystem::path& out) {
  return {NETVMO_DDS_PEER,          "peer",
          std::to_string(domain),   std::to_string(self),
          std::to_string(1 - self), std::to_string(kRounds),
          std::to_string(writers),  out.string()};
}

}  // namespace

TEST(DdsTransport, LoopbackConfigStaysOnThisMachine) {
  const std::string x = net::loopback_config_xml();
  EXPECT_NE(x.find("<NetworkInterface name=\"lo\" />"), std::string::npos);
  EXPECT_NE(x.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(x.find("<Peer Address=\"127.0.0.1\" />"), std::string::npos);
  const auto first = x.find("<Peer ");
  ASSERT_NE(first, std::string::npos);
  EXPECT_EQ(x.find("<Peer ", first + 1), std::string::npos) << "one peer only";
  for (long pid : {1L, 199L, 200L, 4194304L}) {
    EXPECT_GE(net::domain_from_pid(pid), 1);
    EXPECT_LE(net::domain_from_pid(pid), 200);
  }
}

TEST(DdsTransport, TwoProcessesExchangeInLockStep) {
  const auto dir = test::scratch_dir("dds_two");
  const int domain = net_test::loopback_domain(dir);
  const auto res = net_test::run_all(
      {peer_cmd(domain, 0, 1, dir / "p0.txt"), peer_cmd(domain, 1, 1, dir / "p1.txt")}, dir, 30.0);
  for (size_t k = 0; k < res.size(); ++k)
    ASSERT_TRUE(res[k].finished && res[k].exit_code == 0)
        << "peer " << k << ": " << net::describe(res[k]) << "\n"
        << test::slurp(dir / ("child_" + std::to_string(k) + ".log"));
  const Reference ref = reference();
  for (int i = 0; i < 2; ++i) {
    const auto log = read_log(dir / ("p" + std::to_string(i) + ".txt"));
    expect_exactly_the_other(log, 1 - i, ref);
    // The same algorithm as in process, to the last bit.
    EXPECT_LE((log.final_estimate.matrix() - ref.final_estimate[i].matrix()).cwiseAbs().maxCoeff(),
              0.0);
    EXPECT_EQ(log.sent, static_cast<unsigned long long>(kRounds));
    EXPECT_EQ(log.received, static_cast<unsigned long long>(kRounds));
    for (auto n : log.refused) EXPECT_EQ(n, 0u);
  }
}

TEST(DdsTransport, RogueParticipantChangesNothingAndIsCounted) {
  const auto dir = test::scratch_dir("dds_rogue");
  const int domain = net_test::loopback_domain(dir);
  // The rogue first publishes NaN and non-rotation messages under each peer's index on its topic,
  // and well-formed ones under another camera's index on both topics, for every round (kept for
  // late joiners), then stays on the topics; the peers wait for its writers.
  const pid_t rogue =
      net::spawn({NETVMO_DDS_PEER, "rogue", std::to_string(domain), std::to_string(kRounds), "20"},
                 dir / "rogue.log");
  const auto res = net_test::run_all(
      {peer_cmd(domain, 0, 2, dir / "p0.txt"), peer_cmd(domain, 1, 2, dir / "p1.txt")}, dir, 30.0);
  ::kill(rogue, SIGKILL);
  ::waitpid(rogue, nullptr, 0);
  for (size_t k = 0; k < res.size(); ++k)
    ASSERT_TRUE(res[k].finished && res[k].exit_code == 0)
        << "peer " << k << ": " << net::describe(res[k]) << "\n"
        << test::slurp(dir / ("child_" + std::to_string(k) + ".log"));
  const Reference ref = reference();
  const auto log0 = read_log(dir / "p0.txt"), log1 = read_log(dir / "p1.txt");
  for (const auto* log : {&log0, &log1}) {
    const int i = log == &log0 ? 0 : 1;
    expect_exactly_the_other(*log, 1 - i, ref);
    EXPECT_LE((log->final_estimate.matrix() - ref.final_estimate[i].matrix()).cwiseAbs().maxCoeff(),
              0.0);
    ASSERT_EQ(log->refused.size(), 5u);
    // Another sender's index on a neighbour's topic is dropped by the transport, never seen by
    // the observer (one sample a round).
    EXPECT_EQ(log->refused[static_cast<size_t>(obs::MessageVerdict::not_a_neighbour)], 0u);
    EXPECT_EQ(log->foreign, static_cast<unsigned long long>(kRounds));
  }
  // Camera 1 gets camera 0's NaN poses; camera 0 gets camera 1's sheared rotations.
  EXPECT_GE(log1.refused[static_cast<size_t>(obs::MessageVerdict::not_finite)], 1u);
  EXPECT_GE(log0.refused[static_cast<size_t>(obs::MessageVerdict::not_a_rotation)], 1u);
}

// The Estimate type is keyed by its sender: every camera's estimates are one instance, so a
// history keeps each sender's own. Two writers on one topic (no security here, so nothing stops
// the second) each write three rounds; a reader that keeps the last sample holds one per sender.
TEST(DdsTransport, EstimatesAreKeyedBySender) {
  ASSERT_EQ(netvmo_msg_Estimate_desc.m_nkeys, 1u);
  EXPECT_STREQ(netvmo_msg_Estimate_desc.m_keys[0].m_name, "sender");
  const auto dir = test::scratch_dir("dds_keyed");
  const int domain = net_test::loopback_domain(dir);
  const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
  ASSERT_GT(participant, 0);
  const dds_entity_t topic = dds_create_topic(participant, &netvmo_msg_Estimate_desc,
                                              "netvmo_keyed_test", nullptr, nullptr);
  ASSERT_GT(topic, 0);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(10));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  const dds_entity_t reader = dds_create_reader(participant, topic, q, nullptr);
  const dds_entity_t w1 = dds_create_writer(participant, topic, q, nullptr),
                     w2 = dds_create_writer(participant, topic, q, nullptr);
  dds_delete_qos(q);
  ASSERT_GT(reader, 0);
  ASSERT_GT(w1, 0);
  ASSERT_GT(w2, 0);
  netvmo_msg_Estimate m{};
  m.rotation[0] = m.rotation[4] = m.rotation[8] = 1.0;
  for (unsigned long long round = 1; round <= 3; ++round)
    for (const auto& [writer, sender] : {std::pair{w1, 1}, std::pair{w2, 2}}) {
      m.sender = sender;
      m.round = round;
      ASSERT_EQ(dds_write(writer, &m), DDS_RETCODE_OK);
    }
  // Same participant: delivery is synchronous; wait (bounded) all the same.
  void* samples[8] = {};
  dds_sample_info_t infos[8];
  std::vector<std::pair<int, unsigned long long>> held;
  for (int tries = 0; tries < 200 && held.size() < 2; ++tries) {
    const dds_return_t n = dds_read(reader, samples, infos, 8, 8);
    ASSERT_GE(n, 0);
    held.clear();
    for (int k = 0; k < n; ++k)
      if (infos[k].valid_data) {
        const auto* e = static_cast<const netvmo_msg_Estimate*>(samples[k]);
        held.emplace_back(e->sender, e->round);
      }
    dds_return_loan(reader, samples, n);
    if (held.size() < 2) dds_sleepfor(DDS_MSECS(10));
  }
  std::sort(held.begin(), held.end());
  EXPECT_EQ(held, (std::vector<std::pair<int, unsigned long long>>{{1, 3}, {2, 3}}));
  dds_delete(participant);
}
