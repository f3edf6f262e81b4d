// netvmo: cooperative 3D pose estimation of a tagged target by a camera network, with the
// networked visual motion observer under imperfect visibility.
#include <cstdio>
#include <cstdlib>

#include "commands.hpp"

int main(int argc, char** argv) {
  // A corrupt or truncated video is reported once, by netvmo, naming the file; FFmpeg's own
  // messages ("moov atom not found", "overread") are silenced unless the user asks for them.
  ::setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", /*overwrite=*/0);
  CLI::App app{
      "netvmo: a network of cameras cooperatively estimates the pose of an AprilTag-tagged target\n"
      "with the networked visual motion observer (Hatanaka, Nishi, Fujita)."};
  app.name("netvmo");
  app.set_version_flag("--version", "netvmo 0.1.0");
  app.footer("Run 'netvmo <command> --help' for a command's options and defaults.");
  app.require_subcommand(1, 1);
  app.fallthrough(false);
  int exit_code = 0;
  netvmo::tools::add_simulate(app, exit_code);
  netvmo::tools::add_render(app, exit_code);
  netvmo::tools::add_bag(app, exit_code);
  netvmo::tools::add_play(app, exit_code);
  netvmo::tools::add_detect(app, exit_code);
  netvmo::tools::add_calibrate(app, exit_code);
  netvmo::tools::add_run(app, exit_code);
  netvmo::tools::add_sweep(app, exit_code);
  netvmo::tools::add_trajectories(app, exit_code);
  netvmo::tools::add_demo(app, exit_code);
  netvmo::tools::add_bench(app, exit_code);
  netvmo::tools::add_node(app, exit_code);
  netvmo::tools::add_launch(app, exit_code);
  netvmo::tools::add_merge(app, exit_code);
  netvmo::tools::add_security(app, exit_code);
  if (argc == 1) {
    std::fputs(app.help().c_str(), stdout);
    return 1;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return exit_code;
}
