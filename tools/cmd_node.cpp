// netvmo node: one camera of a dataset as its own process, exchanging estimates with its
// neighbours over Cyclone DDS (normally started by `netvmo launch`).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "run_options.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

void add_async_options(CLI::App& cmd, double& speed, double& stale, double& drop, double& delay,
                       std::uint64_t& seed) {
  cmd.add_option("--speed", speed,
                 "async: camera time per wall time (1 = real time; 0.01 to 100: slower than "
                 "0.01 a 10 s recording takes over 15 minutes)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 100.0));
  cmd.add_option("--stale", stale,
                 "async: staleness bound [s of camera time]; a neighbour's estimate older than "
                 "this leaves the mutual term until it is heard again (at most 3600)")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 3600.0));
  cmd.add_option("--drop", drop, "async: probability that a received message is dropped")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd.add_option("--delay", delay,
                 "async: every received message reaches the observer this late [ms]; at most "
                 "10000 (delayed messages are held in memory: ~3,000 a second for 5 cameras)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  cmd.add_option("--seed", seed, "Seed of the injected drops (combined with the camera id)")
      ->capture_default_str();
}

void add_live_options(CLI::App& cmd, bool& on, net::LiveSettings& live) {
  cmd.add_flag("--live", on,
               "Live: every camera's images from its ROS 2 image topic (network.yaml's "
               "image_topic, read best-effort, which also receives reliable publishers; its "
               "calibration from calib/, else the first message of its camera_info_topic), on "
               "their stamps (async); DATASET holds network.yaml and calib/ only");
  cmd.add_option("--duration", live.duration_s,
                 "live: a camera's run ends at its first image this long [s of image time] after "
                 "its first one (0 = no bound)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e7));
  cmd.add_option("--idle", live.idle_s,
                 "live: a camera's run ends when no image has come for this long [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 3600.0));
  cmd.add_option("--lag", live.lag_s,
                 "live: a node runs this far [s] behind its images (frame k is integrated once "
                 "image k+1 has come: one frame interval plus delivery)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 60.0));
}

void add_node(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out, mode = "lockstep";
    int camera = 0, domain = -1, frames = 0, ros_wait_readers = 0;
    double timeout = 20.0, speed = 1.0, stale = 0.25, drop = 0.0, delay = 0.0, start_at = 0.0;
    double clock_offset = 0.0;
    std::uint64_t seed = 0;
    bool resume = false, in_place = false, live = false;
    std::string start_file, security;
    net::LiveSettings live_settings;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "node", "Run one camera of a dataset as its own process, exchanging over Cyclone DDS");
  cmd->footer(
      "Reads network.yaml and the camera's own calibration and frames. Writes OUT/node_<id>.csv\n"
      "(per frame: detection, PnP pose, networked and independent estimates, %.17g),\n"
      "OUT/node_<id>_links.csv (the neighbours heard at each frame) and OUT/node_<id>.json\n"
      "(message statistics). Without CYCLONEDDS_URI it writes and uses the loopback-only\n"
      "configuration OUT/cyclonedds.xml. OUT is this node's own folder, built in\n"
      "OUT.partial-<pid> and swapped into place when the node ends (a killed node leaves the\n"
      "previous OUT intact, and its finished rows in OUT.partial-<pid>/node_<id>.csv.partial),\n"
      "locked by OUT.lock. With --in-place (what launch passes) the node writes straight into\n"
      "OUT, a folder inside launch's own staging folder.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder")->required();
  cmd->add_option("--camera", o->camera, "This node's camera id (network.yaml)")->required();
  cmd->add_option("--out", o->out, "This node's output folder")->required();
  cmd->add_flag("--in-place", o->in_place,
                "Write straight into OUT, without a lock, staging folder or swap: for a caller "
                "that makes OUT crash safe itself (launch: OUT lies inside its staging folder)");
  cmd->add_option("--mode", o->mode,
                  "Exchange: lockstep (wait for every neighbour's message of each round: the "
                  "in-process algorithm) or async (paced on the camera's timestamps, latest value "
                  "of each neighbour)")
      ->check(CLI::IsMember({"lockstep", "async"}))
      ->capture_default_str();
  add_async_options(*cmd, o->speed, o->stale, o->drop, o->delay, o->seed);
  cmd->add_option("--start-at", o->start_at,
                  "async: common start, seconds since the epoch (0 = now); a node started later "
                  "joins at the current frame")
      ->capture_default_str();
  cmd->add_option("--start-file", o->start_file,
                  "async: instead of --start-at, write node_<id>.ready next to this file once set "
                  "up, then wait (at most --timeout) for this file to hold the common start");
  cmd->add_option("--clock-offset", o->clock_offset,
                  "async: emulate a host whose clock is this many seconds off: the node's stamps "
                  "and its exchange's clock are shifted, its images still come in real time "
                  "(docs/processes.md, \"Clocks\")")
      ->capture_default_str()
      ->check(CLI::Range(-86400.0, 86400.0));
  cmd->add_flag("--resume", o->resume,
                "async restart: keep the rows a killed predecessor finished before the frame this "
                "node joins at (node_<id>.csv.partial: in its staging folder OUT.partial-<pid>, "
                "which this node takes over, or with --in-place in OUT)");
  cmd->add_option("--domain", o->domain, "DDS domain id (the same for every node of a run)")
      ->required()
      ->check(CLI::Range(0, 230));
  cmd->add_option("--frames", o->frames,
                  "The dataset's frame count (0 = network.yaml's frames or this camera's count)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", o->timeout,
                  "Longest wait [s] for a neighbour's message of a round before failing (at most "
                  "an hour)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 3600.0));
  add_live_options(*cmd, o->live, o->live_settings);
  cmd->add_option("--ros-wait-readers", o->ros_wait_readers,
                  "Before the first frame, wait (at most --timeout) until this many readers match "
                  "the camera's average_pose topic")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--security", o->security,
                  "DDS Security: this folder's cam_<id> identity, certificates and permissions "
                  "(netvmo security init; docs/processes.md, \"Security\")");
  cmd->add_option("--image-topic", o->live_settings.image_topic,
                  "live (implies --live): this ROS 2 image topic instead of network.yaml's "
                  "(sensor_msgs/msg/Image, or CompressedImage for a name ending in /compressed)");
  cmd->add_option("--camera-info-topic", o->live_settings.camera_info_topic,
                  "live: the camera's calibration from the first sensor_msgs/msg/CameraInfo of "
                  "this topic when calib/ has none");
  add_run_options(*cmd, o->run, /*in_process_transport=*/false);
  cmd->callback([o, &exit_code, cmd] {
    exit_code = guarded("node", [&] {
      const bool live = o->live || !o->live_settings.image_topic.empty();
      if (live && cmd->count("--mode") == 0) o->mode = "async";  // a live camera's own clock
      if (!live && (!o->live_settings.camera_info_topic.empty() || cmd->count("--duration") ||
                    cmd->count("--idle") || cmd->count("--lag")))
        throw InputError("--camera-info-topic, --duration, --idle and --lag need --live");
      net::NodeSettings no;
      no.run = to_image_run_options(o->run);
      io::check_output_apart(o->out, o->dataset);
      // Standalone: the node's own locked staging folder, swapped in at the end (with --resume,
      // the killed predecessor's staging folder is taken over). --in-place (launch): OUT lies in
      // launch's staging folder, which launch swaps in.
      std::optional<io::OutputDir> staged;
      if (!o->in_place) staged.emplace(o->out, "node", o->resume);
      const fs::path dir = staged ? staged->path() : fs::path(o->out);
      io::ensure_directory(dir);
      if (!std::getenv("CYCLONEDDS_URI")) {
        net::write_loopback_config(dir / "cyclonedds.xml");
        net::use_config(dir / "cyclonedds.xml");
      }
      no.run.progress = false;
      no.camera_id = o->camera;
      no.dds.domain = o->domain;
      no.dds.mode = net::parse_mode(o->mode);
      no.dds.timeout_s = o->timeout;
      no.ros_wait_readers = o->ros_wait_readers;
      no.dds.clock_offset_s = o->clock_offset;
      if (o->frames > 0) no.frames = o->frames;
      no.speed = o->speed;
      no.stale_s = o->stale;
      no.drop = o->drop;
      no.delay_ms = o->delay;
      no.seed = o->seed;
      no.resume = o->resume;
      if (live) no.live = o->live_settings;
      if (!o->security.empty())
        no.dds.security = net::security_identity(o->security, net::camera_identity(o->camera));
      if (!o->start_file.empty()) no.start_file = o->start_file;
      if (o->start_at > 0) no.start_epoch = o->start_at;
      std::printf("netvmo node: camera %d, DDS domain %d, %s, config %s\n", o->camera, o->domain,
                  o->mode.c_str(), std::getenv("CYCLONEDDS_URI"));
      std::fflush(stdout);
      const auto s = net::run_node(o->dataset, dir, no);
      if (staged) staged->commit();
      for (const auto& note : s.notes) std::printf("note: %s\n", note.c_str());
      for (const auto& w : s.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
      std::printf(
          "netvmo node: camera %d done: %d frames, %d rounds/frame, %llu sent, %llu received, "
          "%llu late, %llu from non-neighbours, %llu dropped, %llu forgotten, %s kernel drops, "
          "%.2f s\n",
          o->camera, s.frames, s.substeps, static_cast<unsigned long long>(s.stats.sent),
          static_cast<unsigned long long>(s.stats.received),
          static_cast<unsigned long long>(s.stats.late),
          static_cast<unsigned long long>(s.stats.foreign),
          static_cast<unsigned long long>(s.stats.dropped),
          static_cast<unsigned long long>(s.forgotten),
          s.kernel_drops ? std::to_string(*s.kernel_drops).c_str() : "unknown", s.seconds);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
