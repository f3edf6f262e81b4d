// netvmo launch as a library: every camera of a dataset as its own `netvmo node` process on this
// machine (plan, spawn, the async start barrier, supervision with an optional injected kill), and
// the merge of the nodes' outputs into the outputs of `netvmo run` (also `netvmo merge`, of node
// files gathered from several machines). The command line only parses options and draws plots.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::net {

/// A fault to inject into a launch: the node of camera `camera_id` is killed `at` seconds after
/// the start and, with `restart_after` >= 0, started again that many seconds later (--resume).
struct NodeKill {
  int camera_id = 0;
  double at = 0.0;
  double restart_after = -1.0;
};
/// Parses --kill's ID@SECONDS (a camera of `net`, SECONDS >= 0); throws InputError naming the
/// option and network.yaml otherwise.
NodeKill parse_node_kill(const std::string& spec, double restart_after,
                         const io::NetworkConfig& net);

/// Parses --clock-offsets' ID:SECONDS[,ID:SECONDS...] (cameras of `net`, each once, finite
/// seconds) into offsets by camera id; throws InputError naming the option otherwise.
std::map<int, double> parse_clock_offsets(const std::string& spec, const io::NetworkConfig& net);

/// What `netvmo launch` starts. Defaults are the command's.
struct LaunchSettings {
  std::filesystem::path exe;      ///< the netvmo binary the nodes run (net::self_exe())
  std::filesystem::path dataset;  ///< the dataset folder every node reads
  int domain = 0;                 ///< DDS domain
  int frames = 0;                 ///< frames every node runs (--frames)
  double timeout = 600.0;         ///< [s] every node is stopped and the launch fails after this
  double node_timeout = 20.0;     ///< [s] a node fails when a neighbour is silent this long
  bool async = false;             ///< lock-step (false) or each node on its own clock
  /// async: pace (camera seconds per wall second), staleness bound [s], drop probability,
  /// delay [ms] and the seed of the drops.
  double speed = 1.0, stale = 0.25, drop = 0.0, delay = 0.0;
  std::uint64_t seed = 0;
  /// The node's share of the run options (gains, error model, estimator, ...), as arguments.
  std::vector<std::string> run_arguments;
  std::optional<NodeKill> kill;  ///< async only
  /// async: camera id -> its host's emulated clock error [s] (node --clock-offset).
  std::map<int, double> clock_offsets;
  /// Live (async): every node reads its camera's image topic of network.yaml (NodeSettings::live;
  /// the topics there, so image_topic and camera_info_topic are left empty here).
  std::optional<LiveSettings> live;
  /// DDS Security: the security folder every node takes its cam_<id> identity from; empty: none.
  std::filesystem::path security;
  /// Every node waits for this many readers of its average_pose topic before its first frame
  /// (NodeSettings::ros_wait_readers); 0: none.
  int ros_wait_readers = 0;
};

/// Async: the common start is this many seconds after every node is ready.
constexpr double kLaunchStartMargin = 0.25;

struct LaunchOutcome {
  std::vector<ChildResult> nodes;  ///< per camera, in network.yaml order
  double start_epoch = 0.0;        ///< async: the common start (seconds since the epoch)
};

/// The argument vector of camera `camera_id`'s node writing into `nodes_dir`.
std::vector<std::string> node_argv(const LaunchSettings& s, int camera_id,
                                   const std::filesystem::path& nodes_dir);

/// Starts one node per camera of `net` writing into `nodes_dir`, sets the common start once
/// every node is ready (async; printed), supervises them and writes nodes_dir/events.json when a
/// kill was injected. Does not judge the outcome (check_launch does).
LaunchOutcome run_launch(const io::NetworkConfig& net, const LaunchSettings& s,
                         const std::filesystem::path& nodes_dir);

/// Prints one line per node that failed on its own (naming its log as kept in `kept_nodes_dir`)
/// and throws std::runtime_error when one failed or the timeout stopped any (`failed_dir`: where
/// the logs are kept, for the message).
void check_launch(const LaunchOutcome& outcome, const io::NetworkConfig& net,
                  const LaunchSettings& s, const std::filesystem::path& nodes_dir,
                  const std::filesystem::path& kept_nodes_dir,
                  const std::function<std::filesystem::path()>& keep_failed);

/// A node's statistics (node_<id>.json); throws InputError naming the file when it is missing
/// or unreadable.
nlohmann::json read_node_json(const std::filesystem::path& file);

/// The merge of `launch` and `merge`: every node's node_<id>.csv in `nodes_dir` into the outputs
/// of `netvmo run` in `dir` (the same result structure as run_images, the same writers; overlays
/// with `overlays`' settings unless it is null), plus messages.json from the nodes' statistics (a
/// node without them, killed for good in an async run, is null there). Returns the run's summary
/// and the messages.
struct MergedRun {
  nlohmann::json summary;
  nlohmann::json messages;
  /// exchange.json: each node's timing (node_<id>.json "timing": setup, discovery, rounds, round
  /// median and p99) and estimates taken per round, and over the nodes: the slowest discovery,
  /// the median of the nodes' round medians, the largest p99, the mean taken per round.
  nlohmann::json exchange;
};
MergedRun merge_run_outputs(sources::NetworkSource& source, const run::ImageRunSettings& options,
                            const std::filesystem::path& nodes_dir,
                            const std::filesystem::path& dir, int frames, bool allow_gaps,
                            const run::OverlaySettings* overlays);

/// One line on a merged run's exchange (MergedRun::exchange), as printed by launch and merge.
std::string exchange_line(const nlohmann::json& exchange);

/// The per-camera message table of a merged run (sent, received, dropped, late, non-neighbour,
/// rejected), as printed by launch and merge.
std::string message_table(const nlohmann::json& messages, const io::NetworkConfig& net);

}  // namespace netvmo::net
