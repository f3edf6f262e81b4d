// One camera as its own process (`netvmo node`), and the merge of every camera's outputs into
// the outputs of an in-process run (`netvmo launch`).
//
// A node reads network.yaml and its own camera's calibration and frames only, runs its front end,
// its networked CameraObserver and its independent baseline (k_s = 0), and exchanges estimates
// with its neighbours over DdsTransport: per frame, the run's number of rounds of
// publish -> receive -> step, exactly as NetworkedObserver does in process. It writes
//   node_<id>.csv   per frame: detection, PnP pose, networked and independent estimates (%.17g)
//   node_<id>.json  message statistics (sent, received, dropped, late, foreign, refused by
//                   verdict), rounds, warnings
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/image_run.hpp"
#include "netvmo/pipeline/net/dds_transport.hpp"

namespace netvmo::net {

struct NodeOptions {
  pipeline::ImageRunOptions run;  ///< gains, error model, initialisation, rounds, front end
  int camera_id = 0;              ///< this node's camera (network.yaml id)
  DdsSettings dds;
  /// The dataset's frame count (launch passes the whole dataset's; a node alone knows only its
  /// own camera's, or network.yaml's `frames`).
  std::optional<int> frames;
  bool publish_ros_pose = true;  ///< also publish rt/netvmo/camera_<id>/average_pose
};

struct NodeSummary {
  int frames = 0;
  int substeps = 0;
  MessageStats stats;
  std::vector<std::uint64_t> refused;  ///< by obs::MessageVerdict
  std::vector<std::string> warnings;
  double seconds = 0.0;
};

/// Runs camera `options.camera_id` of the dataset; writes node_<id>.csv and node_<id>.json into
/// out_dir. Throws InputError on bad input, DdsTimeout when a neighbour stays silent.
NodeSummary run_node(const std::filesystem::path& dataset, const std::filesystem::path& out_dir,
                     const NodeOptions& options);

/// Reads every camera's node_<id>.csv from nodes_dir and rebuilds the in-process run's result
/// (history with the same evaluation, front-end frames, substeps, step factor) for `frames`
/// frames. Throws InputError naming the file on a missing or malformed one.
pipeline::ImageRunResult merge_nodes(const pipeline::FrameProvider& provider,
                                     const pipeline::ImageRunOptions& options,
                                     const std::filesystem::path& nodes_dir, int frames);

}  // namespace netvmo::net
