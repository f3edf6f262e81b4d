// netvmo node: one camera of a dataset as its own process, exchanging estimates with its
// neighbours over Cyclone DDS (normally started by `netvmo launch`).
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "run_options.hpp"

namespace netvmo::tools {

void add_node(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out, mode = "lockstep";
    int camera = 0, domain = -1, frames = 0;
    double timeout = 20.0;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "node", "Run one camera of a dataset as its own process, exchanging over Cyclone DDS");
  cmd->footer(
      "Reads network.yaml and the camera's own calibration and frames. Writes OUT/node_<id>.csv\n"
      "(per frame: detection, PnP pose, networked and independent estimates, %.17g) and\n"
      "OUT/node_<id>.json (message statistics). Without CYCLONEDDS_URI it writes and uses the\n"
      "loopback-only configuration OUT/cyclonedds.xml.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder")->required();
  cmd->add_option("--camera", o->camera, "This node's camera id (network.yaml)")->required();
  cmd->add_option("--out", o->out, "Output directory")->required();
  cmd->add_option("--mode", o->mode, "Exchange: lockstep (async is not implemented yet)")
      ->check(CLI::IsMember({"lockstep"}))
      ->capture_default_str();
  cmd->add_option("--domain", o->domain, "DDS domain id (the same for every node of a run)")
      ->required()
      ->check(CLI::Range(0, 230));
  cmd->add_option("--frames", o->frames,
                  "The dataset's frame count (0 = network.yaml's frames or this camera's count)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", o->timeout,
                  "Longest wait [s] for a neighbour's message of a round before failing")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  add_run_options(*cmd, o->run);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("node", [&] {
      if (!std::getenv("CYCLONEDDS_URI")) {
        io::ensure_directory(o->out);
        net::write_loopback_config(std::filesystem::path(o->out) / "cyclonedds.xml");
        net::use_config(std::filesystem::path(o->out) / "cyclonedds.xml");
      }
      net::NodeOptions no;
      no.run = to_image_run_options(o->run);
      no.run.progress = false;
      no.camera_id = o->camera;
      no.dds.domain = o->domain;
      no.dds.mode = net::parse_mode(o->mode);
      no.dds.timeout_s = o->timeout;
      if (o->frames > 0) no.frames = o->frames;
      std::printf("netvmo node: camera %d, DDS domain %d, %s, config %s\n", o->camera, o->domain,
                  o->mode.c_str(), std::getenv("CYCLONEDDS_URI"));
      std::fflush(stdout);
      const auto s = net::run_node(o->dataset, o->out, no);
      std::printf(
          "netvmo node: camera %d done: %d frames, %d rounds/frame, %llu sent, %llu received, "
          "%llu late, %llu from non-neighbours, %.2f s\n",
          o->camera, s.frames, s.substeps, static_cast<unsigned long long>(s.stats.sent),
          static_cast<unsigned long long>(s.stats.received),
          static_cast<unsigned long long>(s.stats.late),
          static_cast<unsigned long long>(s.stats.foreign), s.seconds);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
