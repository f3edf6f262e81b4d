// obs::Transport over Eclipse Cyclone DDS: one camera's side of the exchange, in its own
// process. Every camera publishes its EstimateMessage on the topic "netvmo_estimates"
// (type netvmo::msg::Estimate, pipeline/idl/NetvmoEstimate.idl) and reads everyone's; the
// checks of a message (neighbour, finite, rotation, order) are CameraObserver::receive's.
//
// Lock-step: reliable, transient-local (a late-joining reader still gets the first rounds),
// keep-all at the reader. receive() blocks until the current round's message of every
// neighbour has arrived and throws DdsTimeout naming the silent neighbour after
// `timeout_s`. Messages of a later round wait for their round; everything else (non-neighbours,
// earlier rounds, malformed poses) is handed on at once so that the observer counts it.
// Async: reliable, volatile, a bounded reader history; receive() never blocks and hands on
// whatever arrived (the observer keeps the latest message of each neighbour).
#pragma once

#include <cstdint>
#include <deque>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/observer/transport.hpp"

namespace netvmo::net {

enum class Mode { lockstep, async };
Mode parse_mode(const std::string& s);
const char* to_string(Mode m);

struct DdsSettings {
  int domain = 0;  ///< DDS domain id (the Cyclone configuration comes from CYCLONEDDS_URI)
  Mode mode = Mode::lockstep;
  double timeout_s = 20.0;  ///< lock-step: longest wait for a neighbour's message of a round
  std::string topic = "netvmo_estimates";
  /// This camera's graph_digest() of network.yaml, sent with every estimate; a received estimate
  /// carrying another non-zero digest throws GraphMismatch. 0: none sent, nothing checked.
  std::uint64_t graph_digest = 0;
};

/// 64-bit FNV-1a digest of a communication graph: the camera ids in network.yaml order, then the
/// edges as sorted (smaller id, larger id) pairs. Never 0.
std::uint64_t graph_digest(const std::vector<int>& camera_ids,
                           const std::vector<std::pair<int, int>>& edges_by_id);

/// A neighbour's network.yaml graph differs from this camera's.
struct GraphMismatch : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A neighbour stayed silent past the lock-step timeout.
struct DdsTimeout : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What crossed this camera's side of the transport.
struct MessageStats {
  std::uint64_t sent = 0;      ///< estimates published
  std::uint64_t received = 0;  ///< samples taken from the topic (own ones excluded)
  std::uint64_t dropped = 0;   ///< discarded on purpose before the observer (fault injection)
  std::uint64_t late = 0;      ///< a neighbour's message of an earlier round than expected
  std::uint64_t foreign = 0;   ///< from a sender that is not a neighbour
};

class DdsTransport final : public obs::Transport {
 public:
  /// `self`: this camera's index; `neighbours`: its N_i (indices); `labels`: camera ids by index
  /// (for messages and the ROS 2 topic name). Creates the participant, topics, writers and
  /// reader; throws std::runtime_error when Cyclone DDS refuses (bad configuration, ...).
  DdsTransport(int self, std::vector<int> neighbours, std::vector<int> labels,
               DdsSettings settings);
  ~DdsTransport() override;
  DdsTransport(const DdsTransport&) = delete;
  DdsTransport& operator=(const DdsTransport&) = delete;

  void send(const obs::EstimateMessage& m) override;
  void receive(int receiver, std::vector<obs::EstimateMessage>& out) override;

  /// Publishes the camera's estimate of the average pose as geometry_msgs/msg/PoseStamped on
  /// rt/netvmo/camera_<id>/average_pose (frame_id "world", stamp = t).
  void publish_average_pose(const obs::SE3& g_w, double t);

  /// Waits until every reliable reader has acknowledged what this camera sent (before exit).
  void flush(double timeout_s);

  /// Waits until at least `count` writers (this camera's own included) match the estimates
  /// reader, or `timeout_s` passes; returns whether they did.
  bool wait_for_writers(int count, double timeout_s);

  const MessageStats& stats() const { return stats_; }

 private:
  void take_all();

  int self_;
  std::vector<int> neighbours_, labels_;
  DdsSettings settings_;
  std::int32_t participant_ = 0, topic_ = 0, writer_ = 0, reader_ = 0;
  std::int32_t pose_topic_ = 0, pose_writer_ = 0, waitset_ = 0, readcond_ = 0;
  std::uint64_t own_writer_handle_ = 0;
  std::uint64_t round_ = 0;  ///< the round of this camera's last send()
  std::deque<obs::EstimateMessage> pending_;
  MessageStats stats_;
};

/// Publishes arbitrary estimate messages on the estimates topic (tests: a rogue participant).
class RawEstimateWriter {
 public:
  RawEstimateWriter(int domain, const std::string& topic = "netvmo_estimates");
  ~RawEstimateWriter();
  RawEstimateWriter(const RawEstimateWriter&) = delete;
  RawEstimateWriter& operator=(const RawEstimateWriter&) = delete;
  /// Writes a message with the given 4x4 pose entries as they are (no checks).
  void write(const obs::EstimateMessage& m);
  /// Number of readers currently matched.
  int matched_readers() const;

 private:
  std::int32_t participant_ = 0, topic_ = 0, writer_ = 0;
};

/// One geometry_msgs/msg/PoseStamped as read from rt/netvmo/camera_<id>/average_pose.
struct PoseStampedSample {
  int sec = 0;
  unsigned nanosec = 0;
  std::string frame_id;
  obs::Vec3 position = obs::Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// Reads a camera's average-pose topic the way a ROS 2 subscriber would (tests, tools).
class PoseStampedReader {
 public:
  PoseStampedReader(int domain, int camera_id);
  ~PoseStampedReader();
  PoseStampedReader(const PoseStampedReader&) = delete;
  PoseStampedReader& operator=(const PoseStampedReader&) = delete;
  /// Every sample that arrived within `timeout_s` (returns early once some have).
  std::vector<PoseStampedSample> take(double timeout_s);

 private:
  std::int32_t participant_ = 0, topic_ = 0, reader_ = 0, waitset_ = 0, readcond_ = 0;
};

}  // namespace netvmo::net
