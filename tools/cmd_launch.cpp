// netvmo launch: every camera of a dataset as its own `netvmo node` process on this machine,
// exchanging over Cyclone DDS (loopback only), supervised, and their outputs merged into the
// outputs of `netvmo run`.
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/launch.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/sources/topic_network.hpp"
#include "run_options.hpp"
#include "run_plots.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The node's share of the run options (outputs and frame limits are the launcher's).
std::vector<std::string> forwarded(const RunCliOptions& o) {
  std::vector<std::string> a = {"--ke",        io::exact_text(o.k_e),
                                "--ks",        io::exact_text(o.k_s),
                                "--error",     o.error,
                                "--init",      o.init,
                                "--rounds",    std::to_string(o.rounds),
                                "--decimate",  io::exact_text(o.decimate),
                                "--refine",    o.refine,
                                "--estimator", o.estimator};
  if (o.keep_going) a.push_back("--keep-going");
  for (auto& s : search_arguments(o.tracking)) a.push_back(std::move(s));
  return a;
}

// The merge of `launch` and `merge` (net::merge_run_outputs), its plots and its message table;
// returns the summary (for print_run_summary once `dir` is in place).
json merge_and_report(sources::NetworkSource& source, const run::ImageRunSettings& options,
                      const RunCliOptions& cli, const fs::path& nodes, const fs::path& dir,
                      int frames, bool allow_gaps) {
  run::OverlaySettings overlays;
  overlays.camera_videos = cli.camera_videos;
  const auto merged = net::merge_run_outputs(source, options, nodes, dir, frames, allow_gaps,
                                             cli.no_overlays ? nullptr : &overlays);
  if (!cli.no_plots) {
    plot_run(dir, source.network());
  }
  std::printf("%s", net::message_table(merged.messages, source.network()).c_str());
  std::printf("%s", net::exchange_line(merged.exchange).c_str());
  return merged.summary;
}

}  // namespace

void add_launch(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/launch";
    int domain = -1, ros_wait_readers = 0;
    std::uint64_t seed = 0;
    double timeout = 600.0, node_timeout = 20.0;
    std::string mode = "lockstep", kill, clock_offsets;
    double speed = 1.0, stale = 0.25, drop = 0.0, delay = 0.0, restart_after = -1.0;
    bool live = false;
    net::LiveSettings live_settings;
    std::string security;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "launch", "Run every camera as its own process over Cyclone DDS (this machine only)");
  cmd->footer(
      "Writes OUT/cyclonedds.xml (loopback only), starts one `netvmo node` per camera\n"
      "(lock-step by default), and merges their outputs into exactly those of `netvmo run`:\n"
      "OUT/estimates.csv, energies.csv, errors.csv, summary.json, plots and overlays/, plus\n"
      "OUT/nodes/ (per node: node_<id>.csv, node_<id>_links.csv, node_<id>.json and\n"
      "node_<id>.log; the nodes write there with --in-place) and OUT/messages.json. OUT is built "
      "in OUT.partial-<pid> and swapped into place at the end\n"
      "(a killed launch leaves the previous OUT intact), locked by OUT.lock; when a node fails\n"
      "the unfinished folder is kept as OUT.failed/ for its logs.\n"
      "With --live, DATASET holds network.yaml (each camera's image_topic) and calib/ only; every\n"
      "node reads its camera's ROS 2 topic (e.g. from a driver or `netvmo play`) until the\n"
      "stream ends (--idle, --duration); the outputs are on the grid of the images' stamps and\n"
      "have no overlays (docs/ros2.md).");
  cmd->add_option("DATASET", o->dataset, "Dataset folder")->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--domain", o->domain,
                  "DDS domain id (default: derived from this process's id, printed)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--mode", o->mode,
                  "lockstep (the in-process algorithm, outputs equal to `netvmo run`) or async "
                  "(each node paced on its camera's timestamps from a common start)")
      ->check(CLI::IsMember({"lockstep", "async"}))
      ->capture_default_str();
  add_async_options(*cmd, o->speed, o->stale, o->drop, o->delay, o->seed);
  cmd->add_option("--kill", o->kill,
                  "async: ID@T kills camera ID's node T seconds (wall) after the start");
  cmd->add_option("--clock-offsets", o->clock_offsets,
                  "async: ID:S[,ID:S...] runs camera ID's node as on a host whose clock is S "
                  "seconds off (node --clock-offset; docs/processes.md, \"Clocks\")");
  cmd->add_option("--restart-after", o->restart_after,
                  "async: restart the killed node this many seconds later (it joins at the "
                  "current frame, with a new incarnation)")
      ->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--timeout", o->timeout,
                  "Stop every node and fail after this many seconds (at most a day)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  cmd->add_option("--node-timeout", o->node_timeout,
                  "A node fails when a neighbour is silent this long [s] in a round (at most an "
                  "hour)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 3600.0));
  add_live_options(*cmd, o->live, o->live_settings);
  cmd->add_option("--ros-wait-readers", o->ros_wait_readers,
                  "Every node waits (at most --node-timeout) before its first frame until this "
                  "many readers match its camera's average_pose topic")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--security", o->security,
                  "DDS Security: every node with its cam_<id> identity of this folder (netvmo "
                  "security init)");
  add_run_options(*cmd, o->run, /*in_process_transport=*/false);
  cmd->callback([o, &exit_code, cmd] {
    exit_code = guarded("launch", [&] {
      const auto options = to_image_run_options(o->run);
      if (!o->live && (cmd->count("--duration") || cmd->count("--idle") || cmd->count("--lag")))
        throw InputError("--duration, --idle and --lag need --live");
      if (o->live) {
        if (cmd->count("--mode") && o->mode != "async")
          throw InputError("--live runs every node on its images' stamps: --mode async");
        if (!o->kill.empty()) throw InputError("--kill needs a recorded dataset, not --live");
        o->mode = "async";
        o->run.no_overlays = true;  // no images are kept
      }
      std::unique_ptr<sources::NetworkSource> source;
      if (o->live) {
        auto topics = std::make_unique<sources::TopicNetwork>(o->dataset);
        for (size_t i = 0; i < topics->network().cameras.size(); ++i) topics->image_topic(i);
        source = std::move(topics);
      } else {
        source = sources::open_dataset_source(o->dataset, {}, options.keep_going);
      }
      sources::require_static_cameras(*source, "netvmo launch");
      sources::require_single_target(*source, "netvmo launch");
      const auto& netcfg = source->network();
      for (const auto& w : source->warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
      run::checked_rounds(1.0 / netcfg.fps, options.runner.k_e, options.runner.k_s,
                          run::network_graph(netcfg).max_degree(), options.runner.rounds);
      int frames = source->frame_count();  // live: 0 (the nodes' rows decide)
      if (options.max_frames)
        frames = o->live ? *options.max_frames : std::min(frames, *options.max_frames);

      for (const auto& note : source->notes()) std::printf("note: %s\n", note.c_str());
      const bool async = o->mode == "async";
      if (!async && (o->drop > 0 || o->delay > 0 || !o->kill.empty() || o->restart_after >= 0 ||
                     !o->clock_offsets.empty()))
        throw InputError(
            "--drop, --delay, --kill, --restart-after and --clock-offsets need --mode async");
      if (!async)
        if (auto m = sources::clock_mismatch(*source))
          throw InputError(*m + ": lock-step needs one clock for every camera (use --mode async)");
      std::optional<net::NodeKill> kill;
      if (!o->kill.empty())
        kill = net::parse_node_kill(o->kill, o->restart_after, netcfg);
      else if (o->restart_after >= 0)
        throw InputError("--restart-after needs --kill ID@T");

      io::check_output_apart(o->out, o->dataset);
      io::OutputDir out(o->out, "launch");
      const fs::path dir = out.path(), nodes = dir / "nodes";
      io::ensure_directory(nodes);
      const int domain = o->domain >= 0 ? o->domain : net::domain_from_pid(::getpid());
      net::write_loopback_config(dir / "cyclonedds.xml");
      net::use_config(dir / "cyclonedds.xml");
      std::printf("netvmo launch: %zu nodes, DDS domain %d, loopback only (%s)\n",
                  netcfg.cameras.size(), domain, (dir / "cyclonedds.xml").string().c_str());
      std::fflush(stdout);

      net::LaunchSettings ls;
      ls.exe = net::self_exe();
      ls.dataset = o->dataset;
      ls.domain = domain;
      ls.frames = frames;
      ls.timeout = o->timeout;
      ls.node_timeout = o->node_timeout;
      ls.ros_wait_readers = o->ros_wait_readers;
      ls.async = async;
      ls.speed = o->speed;
      ls.stale = o->stale;
      ls.drop = o->drop;
      ls.delay = o->delay;
      ls.seed = o->seed;
      ls.run_arguments = forwarded(o->run);
      ls.kill = kill;
      if (!o->clock_offsets.empty())
        ls.clock_offsets = net::parse_clock_offsets(o->clock_offsets, netcfg);
      if (o->live) ls.live = o->live_settings;
      if (!o->security.empty()) {
        for (const auto& c : netcfg.cameras)  // every node's files, before any starts
          net::security_identity(o->security, net::camera_identity(c.id));
        ls.security = fs::absolute(o->security);
      }
      const auto outcome = net::run_launch(netcfg, ls, nodes);
      // The logs of a failed launch are kept in OUT.failed/; OUT is untouched.
      net::check_launch(outcome, netcfg, ls, nodes, fs::path(o->out + ".failed") / "nodes",
                        [&] { return out.keep_failed(); });

      const json s = merge_and_report(*source, options, o->run, nodes, dir, frames, async);
      out.commit();
      print_run_summary(s, o->out);
      return 0;
    });
  });
}

void add_merge(CLI::App& app, int& exit_code) {
  struct Options {
    std::string nodes, dataset, out;
    bool no_overlays = false, no_plots = false;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = add_command(
      app, "merge", "Merge node outputs gathered into one folder (e.g. from several machines)",
      "NODES holds node_<id>.csv and node_<id>.json of every camera of the dataset's\n"
      "network.yaml, as `netvmo node` writes them (a node killed for good: its\n"
      "node_<id>.csv.partial). The gains, error model, initialisation, rounds, mode and frame\n"
      "count are read from the nodes' statistics and must agree. Writes the outputs of\n"
      "`netvmo launch` into OUT: estimates.csv, energies.csv, errors.csv, summary.json,\n"
      "messages.json, plots and overlays/. OUT is built in OUT.partial-<pid> and swapped into\n"
      "place at the end, locked by OUT.lock (as launch's); it may not hold NODES.");
  cmd->add_option("NODES", o->nodes, "Folder of the nodes' outputs")->required();
  cmd->add_option("--dataset", o->dataset, "The dataset the nodes ran on")->required();
  cmd->add_option("--out", o->out, "Output directory")->required();
  cmd->add_flag("--no-overlays", o->no_overlays, "Do not write overlays/");
  cmd->add_flag("--no-plots", o->no_plots, "Do not draw energies.png and errors.png");
  cmd->callback([o, &exit_code] {
    exit_code = guarded("merge", [&] {
      // A live launch's nodes (node --live) ran on a folder without images.
      std::unique_ptr<sources::NetworkSource> source;
      if (sources::is_topic_network(o->dataset))
        source = std::make_unique<sources::TopicNetwork>(o->dataset);
      else
        source = sources::open_dataset_source(o->dataset);
      sources::require_static_cameras(*source, "netvmo merge");
      sources::require_single_target(*source, "netvmo merge");
      const auto& netcfg = source->network();
      for (const auto& w : source->warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
      const fs::path nodes = o->nodes;
      io::check_output_apart(o->out, o->dataset);
      io::check_output_apart(o->out, nodes, "--out", "NODES folder");
      // The run's settings, from the nodes' statistics: every node must have run the same.
      json ref;
      fs::path ref_file;
      for (const auto& c : netcfg.cameras) {
        const auto files = net::node_files(nodes, c.id);
        const fs::path& csv = files.csv;
        if (!fs::exists(csv) && !fs::exists(net::partial_path(csv)))
          throw InputError(csv.string() + ": not found (nor " +
                           net::partial_path(csv).filename().string() + "): camera " +
                           std::to_string(c.id) + "'s node output");
        const fs::path& f = files.json;
        if (!fs::exists(f)) continue;  // checked by the merge (a node killed for good has none)
        const json j = net::read_node_json(f);
        // (null where a key is missing: a difference, or the check below)
        json run = {{"options", j.value("options", json())},
                    {"mode", j.value("mode", json())},
                    {"dataset_frames", j.value("dataset_frames", json())}};
        if (ref.is_null()) {
          ref = run;
          ref_file = f;
          continue;
        }
        for (const auto& [key, v] : run.items())
          if (v != ref[key])
            throw InputError(f.string() + ": " + key + ": " + v.dump() + " differs from " +
                             ref_file.filename().string() + "'s " + ref[key].dump() +
                             " (every node of a run needs the same)");
      }
      if (ref.is_null() || ref["options"].is_null() || ref["dataset_frames"].is_null())
        throw InputError((nodes / "node_<id>.json").string() +
                         ": no node statistics with the run's options in " + nodes.string());
      RunCliOptions cli;
      try {
        // Node files written before the estimator was recorded ran the paper's observer.
        cli.estimator = ref["options"].value("estimator", std::string("vmo"));
        cli.k_e = ref["options"]["k_e"].get<double>();
        cli.k_s = ref["options"]["k_s"].get<double>();
        cli.error = ref["options"]["error"].get<std::string>();
        cli.init = ref["options"]["init"].get<std::string>();
        cli.rounds = ref["options"]["rounds"].get<int>();
      } catch (const std::exception& e) {
        throw InputError(ref_file.string() + ": options: " + e.what());
      }
      cli.no_overlays = o->no_overlays || source->frame_count() == 0;  // live: no images
      cli.no_plots = o->no_plots;
      const bool async = ref["mode"] == "async";
      io::OutputDir out(o->out, "merge");
      const json s = merge_and_report(*source, to_image_run_options(cli), cli, nodes, out.path(),
                                      ref["dataset_frames"].get<int>(), async);
      out.commit();
      print_run_summary(s, o->out);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
