// netvmo play DATASET [--rate X] [--domain D] [--encoding mono8|rgb8|jpeg|png] [--reliable]
// A dataset folder or bag published as ROS 2 camera topics over Cyclone DDS (net/play.hpp).
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/play.hpp"
#include "netvmo/pipeline/progress.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::tools {

void add_play(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset;
    net::PlaySettings play;
    bool no_camera_info = false, quiet = false;
    std::string security;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "play", "Publish a dataset folder or bag as ROS 2 camera topics over DDS",
      "Publishes each camera's images on rt/cam_<id>/image_raw (sensor_msgs/msg/Image) or\n"
      "rt/cam_<id>/image_raw/compressed (CompressedImage), and its calibration on\n"
      "rt/cam_<id>/camera_info (CameraInfo), every image at its time in the dataset\n"
      "(timestamps.csv's; a bag's stamps less the earliest first one; else frame / fps) divided\n"
      "by --rate, header.stamp = that time, frame_id cam_<id> (docs/ros2.md). Best-effort\n"
      "writers (ROS 2's sensor-data QoS) unless --reliable. Without CYCLONEDDS_URI it uses the\n"
      "loopback-only configuration (this machine only, multicast off); ROS 2 on another machine\n"
      "needs a configuration of yours (docs/processes.md, \"Several machines\").");
  cmd->add_option("DATASET", o->dataset, "dataset folder or bag")->required();
  cmd->add_option("--domain", o->play.domain, "DDS domain id")
      ->capture_default_str()
      ->check(CLI::Range(0, 232));
  cmd->add_option("--rate", o->play.rate, "playback speed (1: real time; 0: as fast as possible)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--encoding", o->play.encoding,
                  "mono8 or rgb8 (sensor_msgs Image), jpeg or png (CompressedImage)")
      ->capture_default_str()
      ->check(CLI::IsMember({"mono8", "rgb8", "jpeg", "png"}));
  cmd->add_flag("--reliable", o->play.reliable, "reliable writers (default: best-effort)");
  cmd->add_flag("--no-camera-info", o->no_camera_info, "do not publish camera_info");
  cmd->add_option("--wait-readers", o->play.wait_readers,
                  "before the first image, wait for this many readers of every image topic")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", o->play.timeout_s, "how long --wait-readers waits [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  cmd->add_option("--settle", o->play.settle_s,
                  "where a best-effort reader matches, wait this long before the first image, so "
                  "that the reader has discovered the writers too [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--linger", o->play.linger_s,
                  "after the last image, keep the writers this long for best-effort readers "
                  "(and at most this long for reliable readers' acknowledgements) [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 3600.0));
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  cmd->add_option("--security", o->security,
                  "DDS Security: publish as the `player` identity of this folder (netvmo security "
                  "init)");
  cmd->callback([o, &exit_code]() {
    exit_code = guarded("play", [&]() {
      o->play.camera_info = !o->no_camera_info;
      if (!o->security.empty()) o->play.security = net::security_identity(o->security, "player");
      // The loopback-only configuration, given inline, when the user has none.
      if (!std::getenv("CYCLONEDDS_URI"))
        ::setenv("CYCLONEDDS_URI", net::loopback_config_xml().c_str(), 1);
      auto source = sources::open_dataset_source(o->dataset);
      std::unique_ptr<Progress> bar;
      const auto stats = net::play(*source, o->play, [&](int done, int total) {
        if (!bar) bar = std::make_unique<Progress>("play", total, !o->quiet);
        bar->update(done);
      });
      if (bar) bar->finish();
      std::printf(
          "played %d images of %zu cameras on DDS domain %d in %.2f s (at most %.3f s "
          "behind schedule)\n",
          stats.images, source->network().cameras.size(), o->play.domain, stats.seconds,
          stats.late_s);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
