#include "netvmo/pipeline/net/dds_transport.hpp"

#include <dds/dds.h>

#include <sched.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>

#include "NetvmoEstimate.h"
#include "dds_util.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::net {

Mode parse_mode(const std::string& s) {
  if (s == "lockstep") return Mode::lockstep;
  if (s == "async") return Mode::async;
  throw std::invalid_argument("unknown mode '" + s + "' (lockstep or async)");
}

const char* to_string(Mode m) {
  return m == Mode::lockstep ? "lockstep" : "async";
}

std::uint64_t graph_digest(const std::vector<int>& camera_ids,
                           const std::vector<std::pair<int, int>>& edges_by_id) {
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64
  const auto add = [&h](std::int64_t v) {
    for (int b = 0; b < 8; ++b) {
      h ^= static_cast<std::uint64_t>(v >> (8 * b)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  add(static_cast<std::int64_t>(camera_ids.size()));
  for (int id : camera_ids) add(id);
  std::vector<std::pair<int, int>> e;
  for (const auto& [a, b] : edges_by_id) e.emplace_back(std::min(a, b), std::max(a, b));
  std::sort(e.begin(), e.end());
  add(static_cast<std::int64_t>(e.size()));
  for (const auto& [a, b] : e) {
    add(a);
    add(b);
  }
  return h == 0 ? 1 : h;
}

namespace {

using detail::check;

constexpr int kMaxTake = 64;

dds_qos_t* estimate_qos(Mode mode, bool writer) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(10));
  if (mode == Mode::lockstep) {
    // A reader that joins late still gets the first rounds; a lock-step writer is never many
    // rounds ahead of any reader (at most the graph's diameter).
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    if (writer) {
      dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 256);
      dds_qset_durability_service(q, 0, DDS_HISTORY_KEEP_LAST, 256, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    } else
      dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 256);
  }
  // A camera's reader does not match its own participant's writer: its own estimates would
  // otherwise be delivered back to it every round (copied, waking the waitset, then discarded).
  if (!writer) dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);
  return q;
}

obs::EstimateMessage from_sample(const netvmo_msg_Estimate& s) {
  obs::EstimateMessage m;
  m.sender = s.sender;
  m.incarnation = s.incarnation;
  m.round = s.round;
  m.stamp = s.stamp;
  m.initialized = s.initialized;
  m.g_w = obs::SE3::Identity();
  for (int r = 0; r < 3; ++r) {
    m.g_w.translation()(r) = s.position[r];
    for (int c = 0; c < 3; ++c) m.g_w.linear()(r, c) = s.rotation[3 * r + c];
  }
  const std::uint32_t k = std::min<std::uint32_t>(s.state._length, obs::kConsensusStateSize);
  std::copy(s.state._buffer, s.state._buffer + k, m.state.begin());
  return m;
}

// The sample of `m`, pointing into it (it must outlive the write).
netvmo_msg_Estimate to_sample(const obs::EstimateMessage& m) {
  netvmo_msg_Estimate s{};
  s.sender = m.sender;
  s.incarnation = m.incarnation;
  s.round = m.round;
  s.stamp = m.stamp;
  s.initialized = m.initialized;
  for (int r = 0; r < 3; ++r) {
    s.position[r] = m.g_w.translation()(r);
    for (int c = 0; c < 3; ++c) s.rotation[3 * r + c] = m.g_w.linear()(r, c);
  }
  // The consensus state in place (dds_write only reads it, while `m` lives).
  s.state._buffer = const_cast<double*>(m.state.data());
  s.state._length = s.state._maximum = static_cast<std::uint32_t>(m.state.size());
  s.state._release = false;
  return s;
}

std::string label(const std::vector<int>& labels, int i) {
  return i >= 0 && static_cast<size_t>(i) < labels.size()
             ? std::to_string(labels[static_cast<size_t>(i)])
             : "#" + std::to_string(i);
}

}  // namespace

std::string estimate_topic(const std::string& base, int camera_id) {
  return base + "_" + std::to_string(camera_id);
}

obs::EstimateMessage decode_estimate(const netvmo_msg_Estimate& s, std::uint64_t own_digest,
                                     int self, const std::vector<int>& labels) {
  if (own_digest != 0 && s.graph != 0 && s.graph != own_digest) {
    const std::string other = label(labels, s.sender), me = label(labels, self);
    throw GraphMismatch("camera " + me + " and camera " + other +
                        ": their network.yaml graphs differ (camera " + other +
                        "'s message carries another graph digest; every node of a run "
                        "needs the same network.yaml)");
  }
  return from_sample(s);
}

DdsTransport::DdsTransport(int self, std::vector<int> neighbours, std::vector<int> labels,
                           DdsSettings settings)
    : self_(self),
      neighbours_(std::move(neighbours)),
      labels_(std::move(labels)),
      settings_(std::move(settings)),
      clock_(self_, neighbours_) {
  participant_ =
      create_participant(settings_.domain, settings_.security ? &*settings_.security : nullptr,
                         "create participant (check CYCLONEDDS_URI)");
  try {
    const auto topic = [&](int index) {
      const std::string name =
          estimate_topic(settings_.topic, labels_.at(static_cast<size_t>(index)));
      return check(
          dds_create_topic(participant_, &netvmo_msg_Estimate_desc, name.c_str(), nullptr, nullptr),
          "create topic");
    };
    dds_qos_t* wq = estimate_qos(settings_.mode, true);
    writer_ = dds_create_writer(participant_, topic(self_), wq, nullptr);
    dds_delete_qos(wq);
    check(writer_, "create writer");
    waitset_ = check(dds_create_waitset(participant_), "create waitset");
    for (int j : neighbours_) {  // one reader per neighbour's topic, all on one waitset
      dds_qos_t* rq = estimate_qos(settings_.mode, false);
      const dds_entity_t r = dds_create_reader(participant_, topic(j), rq, nullptr);
      dds_delete_qos(rq);
      readers_.push_back(check(r, "create reader"));
      readconds_.push_back(
          check(dds_create_readcondition(r, DDS_ANY_STATE), "create read condition"));
      check(dds_waitset_attach(waitset_, readconds_.back(), 0), "attach read condition");
    }
  } catch (...) {
    dds_delete(participant_);
    throw;
  }
}

DdsTransport::~DdsTransport() {
  dds_delete(participant_);
}

double DdsTransport::now() const {
  return epoch_seconds() + settings_.clock_offset_s;
}

void DdsTransport::send(const obs::EstimateMessage& m) {
  netvmo_msg_Estimate s = to_sample(m);
  s.graph = settings_.graph_digest;
  // The exchange's own timing (ClockSync): this message's time, and the latest of each neighbour.
  const auto& heard = clock_.echoes();
  echo_buffer_.resize(heard.size());
  for (size_t e = 0; e < heard.size(); ++e)
    echo_buffer_[e] = {heard[e].camera, heard[e].sent, heard[e].received};
  s.echoes._buffer = echo_buffer_.data();
  s.echoes._length = s.echoes._maximum = static_cast<std::uint32_t>(echo_buffer_.size());
  s.echoes._release = false;
  s.sent = now();
  check(dds_write(writer_, &s), "write estimate");
  round_ = m.round;
  ++stats_.sent;
}

void DdsTransport::take_all() {
  void* samples[kMaxTake] = {nullptr};
  dds_sample_info_t infos[kMaxTake];
  for (size_t a = 0; a < readers_.size(); ++a) {
    const dds_entity_t reader = readers_[a];
    for (;;) {
      const dds_return_t n = dds_take(reader, samples, infos, kMaxTake, kMaxTake);
      check(n, "take estimates");
      const double taken = now();  // (after the take: every sample of it had arrived)
      for (dds_return_t k = 0; k < n; ++k) {
        if (!infos[k].valid_data) continue;
        const auto& s = *static_cast<const netvmo_msg_Estimate*>(samples[k]);
        ++stats_.received;
        // Neighbour j's topic carries j's estimates only: a sample under another sender's
        // index there is not j's (a misconfigured or impersonating writer) and is dropped.
        if (s.sender != neighbours_[a]) {
          ++stats_.foreign;
          continue;
        }
        try {
          pending_.push_back(decode_estimate(s, settings_.graph_digest, self_, labels_));
        } catch (const GraphMismatch&) {
          dds_return_loan(reader, samples, n);
          throw;
        }
        echo_in_.clear();
        for (std::uint32_t e = 0; e < s.echoes._length; ++e)
          echo_in_.push_back(
              {s.echoes._buffer[e].camera, s.echoes._buffer[e].sent, s.echoes._buffer[e].received});
        clock_.taken(s.sender, s.sent, taken, echo_in_.data(), echo_in_.size());
        // Stamps are handed on on this camera's clock (the staleness bound compares them with
        // its own time).
        pending_.back().stamp = clock_.to_own_clock(s.sender, s.stamp);
      }
      if (n > 0) dds_return_loan(reader, samples, n);
      if (n < kMaxTake) break;
    }
  }
}

bool DdsTransport::poll(double us) const {
  if (us <= 0.0) return false;
  const auto until =
      std::chrono::steady_clock::now() + std::chrono::duration<double, std::micro>(us);
  for (;;) {
    for (const dds_entity_t c : readconds_)
      if (dds_triggered(c) > 0) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    // Gives the core to a runnable thread, above all this machine's DDS receive threads, which
    // deliver what this one waits for.
    sched_yield();
  }
}

void DdsTransport::receive(int receiver, std::vector<obs::EstimateMessage>& out) {
  out.clear();
  if (receiver != self_)
    throw std::invalid_argument("DdsTransport of camera " + label(labels_, self_) +
                                " asked for camera " + label(labels_, receiver) + "'s messages");
  take_all();  // (every pending message is a neighbour's: take_all reads their topics only)
  if (settings_.mode == Mode::async) {
    out.assign(pending_.begin(), pending_.end());
    pending_.clear();
    return;
  }
  // Lock-step: this round's message of every neighbour (a well-formed one), everything else
  // handed on for the observer to judge; later rounds wait.
  std::vector<bool> have(neighbours_.size(), false);
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    for (auto it = pending_.begin(); it != pending_.end();) {
      const auto& m = *it;
      const auto a = std::find(neighbours_.begin(), neighbours_.end(), m.sender);
      if (m.round > round_) {
        ++it;  // a neighbour already in a later round: keep it for that round
        continue;
      } else if (m.round < round_) {
        ++stats_.late;
      } else if (obs::check_pose(m.g_w) == obs::MessageVerdict::accepted) {
        have[static_cast<size_t>(a - neighbours_.begin())] = true;
      }
      out.push_back(m);
      it = pending_.erase(it);
    }
    const auto missing = std::find(have.begin(), have.end(), false);
    if (missing == have.end()) return;
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (waited >= settings_.timeout_s) {
      const int j = neighbours_[static_cast<size_t>(missing - have.begin())];
      char b[64];
      std::snprintf(b, sizeof b, "%.1f", settings_.timeout_s);
      throw DdsTimeout("camera " + label(labels_, self_) + ": no message of round " +
                       std::to_string(round_) + " from neighbour camera " + label(labels_, j) +
                       " within " + b + " s (is its node running, on DDS domain " +
                       std::to_string(settings_.domain) + "?)");
    }
    if (poll(settings_.poll_us)) {
      take_all();
      continue;
    }
    const double left = std::min(0.5, settings_.timeout_s - waited);
    const dds_return_t rc =
        dds_waitset_wait(waitset_, nullptr, 0, static_cast<dds_duration_t>(left * 1e9));
    check(rc, "wait for estimates");
    take_all();
  }
}

void DdsTransport::flush(double timeout_s) {
  dds_wait_for_acks(writer_, static_cast<dds_duration_t>(timeout_s * 1e9));
}

bool DdsTransport::wait_for_writers(int count, double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    int matched = 0;
    for (const dds_entity_t r : readers_) {
      dds_subscription_matched_status_t st;
      check(dds_get_subscription_matched_status(r, &st), "matched status");
      matched += static_cast<int>(st.current_count);
    }
    if (matched >= count) return true;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s)
      return false;
    dds_sleepfor(DDS_MSECS(10));
  }
}

RawEstimateWriter::RawEstimateWriter(int domain, const std::string& topic,
                                     const SecurityIdentity* security) {
  participant_ = create_participant(domain, security, "create participant (check CYCLONEDDS_URI)");
  topic_ =
      dds_create_topic(participant_, &netvmo_msg_Estimate_desc, topic.c_str(), nullptr, nullptr);
  if (topic_ < 0) dds_delete(participant_);
  check(topic_, "create topic");
  dds_qos_t* q = estimate_qos(Mode::lockstep, true);
  writer_ = dds_create_writer(participant_, topic_, q, nullptr);
  dds_delete_qos(q);
  if (writer_ < 0) dds_delete(participant_);
  check(writer_, "create writer");
}

RawEstimateWriter::~RawEstimateWriter() {
  dds_delete(participant_);
}

void RawEstimateWriter::write(const obs::EstimateMessage& m) {
  const netvmo_msg_Estimate s = to_sample(m);
  check(dds_write(writer_, &s), "write estimate");
}

int RawEstimateWriter::matched_readers() const {
  dds_publication_matched_status_t st;
  check(dds_get_publication_matched_status(writer_, &st), "matched status");
  return static_cast<int>(st.current_count);
}

}  // namespace netvmo::net
