// netvmo launch: every camera of a dataset as its own `netvmo node` process on this machine,
// exchanging over Cyclone DDS (loopback only), supervised, and their outputs merged into the
// outputs of `netvmo run`.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "run_options.hpp"
#include "run_plots.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Async: the common start is this many seconds after every node is ready (set up and matched
// with its neighbours).
constexpr double kStartMargin = 0.25;

double now_epoch() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// The node's share of the run options (outputs and frame limits are the launcher's).
std::vector<std::string> forwarded(const RunCliOptions& o) {
  std::vector<std::string> a = {
      "--ke",       num(o.k_e),      "--ks",     num(o.k_s), "--error",
      o.error,      "--init",        o.init,     "--rounds", std::to_string(o.rounds),
      "--decimate", num(o.decimate), "--refine", o.refine,   "--estimator",
      o.estimator};
  if (o.keep_going) a.push_back("--keep-going");
  for (auto& s : search_arguments(o.tracking)) a.push_back(std::move(s));
  return a;
}

std::string last_line(const fs::path& log) {
  std::ifstream f(log);
  std::string line, last;
  while (std::getline(f, line))
    if (!line.empty()) last = line;
  return last;
}

// Reads a node's statistics (node_<id>.json); throws InputError naming it when unreadable.
json read_node_json(const fs::path& f) {
  if (!fs::exists(f)) throw InputError(f.string() + ": node statistics not found");
  std::ifstream in(f);
  json j;
  try {
    in >> j;
  } catch (const std::exception&) {
    throw InputError(f.string() + ": unreadable node statistics");
  }
  return j;
}

// The merge of `launch` and `merge`: every node's node_<id>.csv in `nodes` into the outputs of
// `netvmo run` in `dir` (the same result structure as run_images, the same writers), plus
// messages.json from the nodes' statistics; prints the message table and returns the summary
// (for print_run_summary once `dir` is in place). A node without statistics (killed for good)
// is listed as such.
json merge_and_report(sources::NetworkSource& provider, const run::ImageRunOptions& options,
                      const RunCliOptions& cli, const fs::path& nodes, const fs::path& dir,
                      int frames, bool allow_gaps) {
  const auto& netcfg = provider.network();
  auto result = net::merge_nodes(provider, options, nodes, frames, allow_gaps);
  json messages = json::object();
  for (const auto& c : netcfg.cameras) {
    const fs::path f = nodes / ("node_" + std::to_string(c.id) + ".json");
    if (allow_gaps && !fs::exists(f)) {  // killed and not restarted: it never finished
      messages[std::to_string(c.id)] = nullptr;
      continue;
    }
    const json j = read_node_json(f);
    messages[std::to_string(c.id)] = j["messages"];
    for (const auto& w : j["warnings"]) result.warnings.push_back(w.get<std::string>());
    result.seconds = std::max(result.seconds, j["seconds"].get<double>());
  }
  io::ensure_directory(dir);
  io::write_file_atomic(dir / "messages.json", messages.dump(2) + "\n");
  if (!cli.no_overlays) {
    run::OverlayWriter overlays(dir, provider);
    const size_t n = netcfg.cameras.size();
    for (int k = 0; k < frames; ++k) {
      std::vector<cv::Mat> images(n);
      for (size_t i = 0; i < n; ++i) {
        if (result.frames[static_cast<size_t>(k)][i].read_failed) continue;
        // Cameras on their own clocks: the image each camera held at this grid time.
        const int own =
            result.source_frames.empty() ? k : result.source_frames[static_cast<size_t>(k)][i];
        if (own >= 0) images[i] = provider.read(i, own);
      }
      overlays(k, images, {result.frames[static_cast<size_t>(k)]},
               {&result.history[static_cast<size_t>(k)]});
    }
    overlays.finish();
  }
  for (size_t k = provider.warnings().size(); k < result.warnings.size(); ++k)
    std::fprintf(stderr, "warning: %s\n", result.warnings[k].c_str());
  const json s = run::write_run_outputs(dir, provider, options, result);
  if (!cli.no_plots) {
    plot_run(dir, netcfg);
  }
  // Every node reads the one estimates topic: messages of non-neighbours are ignored (and
  // counted apart from those refused as malformed or out of order).
  std::printf("messages: camera    sent  received  dropped  late  non-neighbour  rejected\n");
  for (const auto& c : netcfg.cameras) {
    const auto& m = messages[std::to_string(c.id)];
    if (m.is_null()) {
      std::printf("          %6d  (killed, no statistics)\n", c.id);
      continue;
    }
    unsigned long long rejected = 0, foreign = 0;
    for (const auto& [k, v] : m["rejected"].items())
      (k == obs::to_string(obs::MessageVerdict::not_a_neighbour) ? foreign : rejected) +=
          v.get<unsigned long long>();
    std::printf("          %6d  %6llu  %8llu  %7llu  %4llu  %13llu  %8llu\n", c.id,
                m["sent"].get<unsigned long long>(), m["received"].get<unsigned long long>(),
                m["dropped"].get<unsigned long long>(), m["late"].get<unsigned long long>(),
                foreign, rejected);
  }
  return s;
}

}  // namespace

void add_launch(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/launch";
    int domain = -1;
    std::uint64_t seed = 0;
    double timeout = 600.0, node_timeout = 20.0;
    std::string mode = "lockstep", kill;
    double speed = 1.0, stale = 0.25, drop = 0.0, delay = 0.0, restart_after = -1.0;
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
      "the unfinished folder is kept as OUT.failed/ for its logs.");
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
  add_run_options(*cmd, o->run, /*in_process_transport=*/false);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("launch", [&] {
      const auto options = to_image_run_options(o->run);
      require_single_estimator(options);
      auto provider = sources::open_dataset_source(o->dataset, {}, options.keep_going);
      sources::require_static_cameras(*provider, "netvmo launch");
      sources::require_single_target(*provider, "netvmo launch");
      const auto& netcfg = provider->network();
      for (const auto& w : provider->warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
      run::checked_rounds(1.0 / netcfg.fps, options.runner.k_e, options.runner.k_s,
                          run::network_graph(netcfg).max_degree(), options.runner.rounds);
      int frames = provider->frame_count();
      if (options.max_frames) frames = std::min(frames, *options.max_frames);

      for (const auto& note : provider->notes()) std::printf("note: %s\n", note.c_str());
      const bool async = o->mode == "async";
      if (!async && (o->drop > 0 || o->delay > 0 || !o->kill.empty() || o->restart_after >= 0))
        throw InputError("--drop, --delay, --kill and --restart-after need --mode async");
      if (!async)
        if (auto m = sources::clock_mismatch(*provider))
          throw InputError(*m + ": lock-step needs one clock for every camera (use --mode async)");
      net::KillPlan plan;
      bool have_plan = false;
      if (!o->kill.empty()) {
        const auto at = o->kill.find('@');
        int id = -1;
        double t = -1;
        try {
          if (at != std::string::npos) {
            id = std::stoi(o->kill.substr(0, at));
            t = std::stod(o->kill.substr(at + 1));
          }
        } catch (const std::exception&) {
        }
        if (at == std::string::npos || netcfg.index_of(id) < 0 || !(t >= 0))
          throw InputError("--kill " + o->kill + ": expected ID@SECONDS with a camera id of " +
                           netcfg.source);
        plan.index = static_cast<size_t>(netcfg.index_of(id));
        plan.kill_at = t;  // after the common start (made relative to it below)
        plan.restart_after = o->restart_after;
        have_plan = true;
      } else if (o->restart_after >= 0) {
        throw InputError("--restart-after needs --kill ID@T");
      }

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

      const fs::path start_file = nodes / "start.txt";  // async: the common start
      fs::remove(start_file);
      std::fflush(stdout);  // before the children inherit the buffer
      const std::string exe = net::self_exe().string();
      std::vector<pid_t> pids;
      for (const auto& c : netcfg.cameras) {
        std::vector<std::string> argv = {exe,
                                         "node",
                                         o->dataset,
                                         "--camera",
                                         std::to_string(c.id),
                                         "--out",
                                         nodes.string(),
                                         "--in-place",
                                         "--domain",
                                         std::to_string(domain),
                                         "--frames",
                                         std::to_string(frames),
                                         "--timeout",
                                         num(o->node_timeout)};
        for (auto& a : forwarded(o->run)) argv.push_back(std::move(a));
        if (async)
          for (auto a :
               {std::string("--mode"), std::string("async"), std::string("--speed"), num(o->speed),
                std::string("--stale"), num(o->stale), std::string("--drop"), num(o->drop),
                std::string("--delay"), num(o->delay), std::string("--seed"),
                std::to_string(o->seed), std::string("--start-file"), start_file.string()})
            argv.push_back(a);
        const fs::path log = nodes / ("node_" + std::to_string(c.id) + ".log");
        if (have_plan && pids.size() == plan.index) {
          plan.argv = argv;
          plan.argv.push_back("--resume");  // keeps the rows it finished before the kill
          plan.log = log;
        }
        pids.push_back(net::spawn(argv, log));
      }
      double start_at = 0.0;
      if (async) {
        // The common start, once every node is ready (or one has ended, or --node-timeout has
        // passed: then supervise reports it); printed for the record.
        const double give_up = now_epoch() + o->node_timeout;
        for (;;) {
          bool ready = true, ended = false;
          for (size_t i = 0; i < pids.size(); ++i) {
            ready = ready &&
                    fs::exists(nodes / ("node_" + std::to_string(netcfg.cameras[i].id) + ".ready"));
            ended = ended || net::has_exited(pids[i]);
          }
          if (ready || ended || now_epoch() > give_up) break;
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        start_at = now_epoch() + kStartMargin;
        io::write_file_atomic(start_file, num(start_at) + "\n");
        plan.kill_at += start_at - now_epoch();  // supervision starts now
        std::printf(
            "netvmo launch: async, speed %g, staleness %g s, drop %g, delay %g ms, seed %llu, "
            "start at %.3f (epoch)\n",
            o->speed, o->stale, o->drop, o->delay, static_cast<unsigned long long>(o->seed),
            start_at);
        std::fflush(stdout);
      }
      const auto res = net::supervise(pids, o->timeout, true, have_plan ? &plan : nullptr);
      json events = json::object();  // the injected fault, in wall and camera time
      if (have_plan) {
        const auto& r = res[plan.index];
        const auto cam_time = [&](double epoch) { return (epoch - start_at) * o->speed; };
        events["camera"] = netcfg.cameras[plan.index].id;
        events["start_epoch"] = start_at;
        events["speed"] = o->speed;
        if (r.kill_epoch > 0)
          events["kill"] = {{"epoch", r.kill_epoch}, {"camera_time", cam_time(r.kill_epoch)}};
        if (r.restart_epoch > 0)
          events["restart"] = {{"epoch", r.restart_epoch},
                               {"camera_time", cam_time(r.restart_epoch)}};
        io::write_file_atomic(nodes / "events.json", events.dump(2) + "\n");
      }
      // Report the nodes that failed on their own first; the others were stopped because of
      // them, or by the timeout.
      std::vector<int> stopped;
      bool failed = false;
      for (size_t i = 0; i < res.size(); ++i) {
        const int id = netcfg.cameras[i].id;
        if ((res[i].finished && res[i].exit_code == 0) || res[i].planned_kill) continue;
        if (res[i].killed) {
          stopped.push_back(id);
          continue;
        }
        const std::string log = "node_" + std::to_string(id) + ".log";
        const fs::path kept = fs::path(o->out + ".failed") / "nodes" / log;  // see keep_failed
        std::fprintf(stderr, "netvmo launch: node of camera %d failed (%s): %s [%s]\n", id,
                     net::describe(res[i]).c_str(), last_line(nodes / log).c_str(),
                     kept.string().c_str());
        failed = true;
      }
      // The logs of a failed launch are kept in OUT.failed/; OUT is untouched.
      if (failed)
        throw std::runtime_error("a node failed; see " + (out.keep_failed() / "nodes").string());
      if (!stopped.empty()) {
        std::string ids;
        for (int id : stopped) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
        throw std::runtime_error("timeout after " + num(o->timeout) +
                                 " s: stopped the nodes of cameras " + ids + "; see " +
                                 (out.keep_failed() / "nodes").string());
      }

      const json s = merge_and_report(*provider, options, o->run, nodes, dir, frames, async);
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
      auto provider = sources::open_dataset_source(o->dataset);
      sources::require_static_cameras(*provider, "netvmo merge");
      sources::require_single_target(*provider, "netvmo merge");
      const auto& netcfg = provider->network();
      for (const auto& w : provider->warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
      const fs::path nodes = o->nodes;
      io::check_output_apart(o->out, o->dataset);
      io::check_output_apart(o->out, nodes, "--out", "NODES folder");
      // The run's settings, from the nodes' statistics: every node must have run the same.
      json ref;
      fs::path ref_file;
      for (const auto& c : netcfg.cameras) {
        const fs::path csv = nodes / ("node_" + std::to_string(c.id) + ".csv");
        if (!fs::exists(csv) && !fs::exists(net::partial_path(csv)))
          throw InputError(csv.string() + ": not found (nor " +
                           net::partial_path(csv).filename().string() + "): camera " +
                           std::to_string(c.id) + "'s node output");
        const fs::path f = nodes / ("node_" + std::to_string(c.id) + ".json");
        if (!fs::exists(f)) continue;  // checked by the merge (a node killed for good has none)
        const json j = read_node_json(f);
        json run = {{"options", j["options"]},
                    {"mode", j["mode"]},
                    {"dataset_frames", j["dataset_frames"]}};
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
      cli.no_overlays = o->no_overlays;
      cli.no_plots = o->no_plots;
      const bool async = ref["mode"] == "async";
      io::OutputDir out(o->out, "merge");
      const json s = merge_and_report(*provider, to_image_run_options(cli), cli, nodes, out.path(),
                                      ref["dataset_frames"].get<int>(), async);
      out.commit();
      print_run_summary(s, o->out);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
