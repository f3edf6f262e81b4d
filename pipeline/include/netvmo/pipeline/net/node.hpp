// One camera as its own process (`netvmo node`), and the merge of every camera's outputs into
// the outputs of an in-process run (`netvmo launch`).
//
// A node reads network.yaml and its own camera's calibration and frames only, runs its front end,
// its networked CameraObserver and its independent baseline (k_s = 0), and exchanges estimates
// with its neighbours over DdsTransport: per frame, the run's number of rounds of
// publish -> receive -> step, exactly as NetworkedObserver does in process. It writes
//   node_<id>.csv   per frame: detection, PnP pose, networked and independent estimates (%.17g)
//   node_<id>.json  message statistics (sent, received, dropped, late, foreign, refused by
//                   verdict), rounds, warnings, timing (setup, discovery, rounds), and each
//                   neighbour's clock offset as the exchange measured it (ClockSync)
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/net/dds_transport.hpp"
#include "netvmo/pipeline/net/live_camera.hpp"
#include "netvmo/pipeline/run/image_run.hpp"

namespace netvmo::net {

struct NodeSettings {
  run::ImageRunSettings run;  ///< gains, error model, initialisation, rounds, front end
  int camera_id = 0;          ///< this node's camera (network.yaml id)
  DdsSettings dds;
  /// The dataset's frame count (launch passes the whole dataset's; a node alone knows only its
  /// own camera's, or network.yaml's `frames`).
  std::optional<int> frames;
  /// Also publish the camera's ROS 2 topics (RosPublisher: its estimate, measurement and
  /// transforms).
  bool publish_ros_pose = true;
  /// Before its first frame, wait (at most dds.timeout_s; then InputError naming the topic)
  /// until this many readers match the camera's rt/netvmo/camera_<id>/average_pose (a viewer or
  /// recorder that must not miss the first poses; a secured one matches once its handshake is
  /// done). 0: start at once.
  int ros_wait_readers = 0;

  // Async mode only (dds.mode == Mode::async).
  /// Camera time runs at `speed` x wall time: frame k's round r is due at
  /// start + (k dt + r h) / speed. A node behind schedule runs its rounds back to back.
  double speed = 1.0;
  /// The common start (seconds since the epoch, wall clock); default: the node's own start. A
  /// node started after it (a restart) joins at the current frame.
  std::optional<double> start_epoch;
  /// Instead of start_epoch: once set up and matched with its neighbours, the node writes
  /// node_<id>.ready next to this file (not into its output folder, which may be a staging
  /// folder named after its process id) and waits (at most dds.timeout_s) for this file to
  /// hold the common start (seconds since the epoch); `launch` writes it when every node is
  /// ready. A restarted node finds it there and joins late.
  std::optional<std::filesystem::path> start_file;
  /// Staleness bound [s of camera time]: a neighbour whose latest accepted estimate is older
  /// than this (by its stamp) is forgotten (CameraObserver::forget) until heard again.
  double stale_s = 0.25;
  double drop = 0.0;       ///< probability that a received message is dropped (seeded)
  double delay_ms = 0.0;   ///< every received message is handed to the observer this late
  std::uint64_t seed = 0;  ///< seed of the drops (with the camera id)
  /// Live (async only): the camera's images come from its ROS 2 image topic (LiveCamera) and
  /// DATASET holds network.yaml and calib/ only (sources::TopicNetwork). The node's clock is the
  /// images' stamps: frame k is image k, integrated from its stamp to the next image's once that
  /// has come, its rounds due `lag_s` after the wall time the first image came plus their stamp's
  /// distance from it (/ speed); `frames` bounds the frames, the stream's end (LiveSettings) ends
  /// the run. Neither a common start nor a join-late restart applies.
  std::optional<LiveSettings> live;
  /// A restart (`launch --restart-after`): keep the killed predecessor's finished rows of
  /// node_<id>.csv.partial in out_dir (frames before the one this node joins at). `netvmo node`
  /// makes out_dir the predecessor's folder: its staging folder (io::OutputDir with resume), or
  /// with --in-place the folder itself.
  bool resume = false;
};

struct NodeSummary {
  int frames = 0;
  int substeps = 0;
  MessageStats stats;
  std::vector<std::uint64_t> refused;  ///< by obs::MessageVerdict
  std::uint64_t forgotten = 0;         ///< async: neighbours dropped past the staleness bound
  int first_frame = 0;                 ///< async: the frame a (re)started node joined at
  /// A late join: the rounds it ran without its measurement, waiting for every neighbour's
  /// estimate and starting from them (obs::JoinHold); 0 otherwise.
  int join_rounds = 0;
  /// Datagrams the kernel dropped on this node's UDP sockets, their receive buffers full
  /// (socket_drops.hpp; nullopt where the system does not tell): lost images of a best-effort
  /// topic, or messages the exchange resent.
  std::optional<std::uint64_t> kernel_drops;
  std::vector<std::string> warnings;
  std::vector<std::string> notes;  ///< the dataset's (e.g. where the image times come from)
  double seconds = 0.0;
};

/// The files of camera `camera_id`'s node in the folder `dir` it writes to.
struct NodeFiles {
  std::filesystem::path csv;    ///< node_<id>.csv: one row per frame (node_journal.hpp)
  std::filesystem::path links;  ///< node_<id>_links.csv: the effective graph after each frame
  std::filesystem::path json;   ///< node_<id>.json: statistics and the run's options
  std::filesystem::path log;    ///< node_<id>.log: its standard output and error (launch)
};
NodeFiles node_files(const std::filesystem::path& dir, int camera_id);
/// node_<id>.ready, written next to the common start file once the node is set up (async).
std::filesystem::path node_ready_file(const std::filesystem::path& start_file, int camera_id);

/// Where a node writes `file` (node_<id>.csv, node_<id>_links.csv) while it runs: the finished
/// frames, flushed after each, renamed to `file` when the node ends (`file`.partial).
inline std::filesystem::path partial_path(const std::filesystem::path& file) {
  return file.string() + ".partial";
}

/// Runs camera `options.camera_id` of the dataset; writes node_<id>.csv and node_<id>.json into
/// out_dir. Throws InputError on bad input, DdsTimeout when a neighbour stays silent.
NodeSummary run_node(const std::filesystem::path& dataset, const std::filesystem::path& out_dir,
                     const NodeSettings& options);

/// Reads every camera's node_<id>.csv from nodes_dir and rebuilds the in-process run's result
/// (history with the same evaluation, front-end frames, substeps, step factor) for `frames`
/// frames. With `allow_gaps` (async runs with restarts) a frame a node has no row for counts as
/// blind and uninitialised there; otherwise every frame must be present. A source without
/// images (a live network, sources::TopicNetwork) is evaluated on the grid of its nodes' rows'
/// times (`frames` 0: up to the last row). Throws InputError naming the file on a missing or
/// malformed one. `clock_correction` (by camera; empty: none) is subtracted from each node's
/// rows' times: its clock's offset to the reference camera's (ClockAlignment::correction_s).
run::ImageRunResult merge_nodes(const sources::NetworkSource& source,
                                const run::ImageRunSettings& options,
                                const std::filesystem::path& nodes_dir, int frames,
                                bool allow_gaps = false,
                                const std::vector<double>& clock_correction = {});

}  // namespace netvmo::net
