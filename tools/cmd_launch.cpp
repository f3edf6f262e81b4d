// netvmo launch: every camera of a dataset as its own `netvmo node` process on this machine,
// exchanging over Cyclone DDS (loopback only), supervised, and their outputs merged into the
// outputs of `netvmo run`.
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io.hpp"
#include "netvmo/pipeline/net/cyclone_config.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/process.hpp"
#include "netvmo/pipeline/overlay.hpp"
#include "netvmo/pipeline/run_report.hpp"
#include "run_options.hpp"
#include "run_plots.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

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
      "--decimate", num(o.decimate), "--refine", o.refine};
  if (o.keep_going) a.push_back("--keep-going");
  if (o.no_track) a.push_back("--no-track");
  return a;
}

std::string last_line(const fs::path& log) {
  std::ifstream f(log);
  std::string line, last;
  while (std::getline(f, line))
    if (!line.empty()) last = line;
  return last;
}

}  // namespace

void add_launch(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out = "results/launch";
    int domain = -1, seed = 0;
    double timeout = 600.0, node_timeout = 20.0;
    RunCliOptions run;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "launch", "Run every camera as its own process over Cyclone DDS (this machine only)");
  cmd->footer(
      "Writes OUT/cyclonedds.xml (loopback only), starts one `netvmo node` per camera\n"
      "(lock-step), and merges their outputs into exactly those of `netvmo run`:\n"
      "OUT/estimates.csv, energies.csv, errors.csv, summary.json, plots and overlays/, plus\n"
      "OUT/nodes/ (per-node CSV, statistics and log) and OUT/messages.json.");
  cmd->add_option("DATASET", o->dataset, "Dataset folder")->required();
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--domain", o->domain,
                  "DDS domain id (default: derived from this process's id, printed)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--seed", o->seed, "Seed of injected faults (none in lock-step)")
      ->capture_default_str();
  cmd->add_option("--timeout", o->timeout, "Stop every node and fail after this many seconds")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--node-timeout", o->node_timeout,
                  "A node fails when a neighbour is silent this long [s] in a round")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  add_run_options(*cmd, o->run);
  cmd->callback([o, &exit_code] {
    exit_code = guarded("launch", [&] {
      const auto options = to_image_run_options(o->run);
      auto provider = pipeline::open_dataset_provider(o->dataset);
      const auto& netcfg = provider->network();
      for (const auto& w : provider->warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
      int frames = provider->frame_count();
      if (options.max_frames) frames = std::min(frames, *options.max_frames);

      const fs::path dir = o->out, nodes = dir / "nodes";
      io::ensure_directory(nodes);
      const int domain = o->domain >= 0 ? o->domain : net::domain_from_pid(::getpid());
      net::write_loopback_config(dir / "cyclonedds.xml");
      net::use_config(dir / "cyclonedds.xml");
      std::printf("netvmo launch: %zu nodes, DDS domain %d, loopback only (%s)\n",
                  netcfg.cameras.size(), domain, (dir / "cyclonedds.xml").string().c_str());
      std::fflush(stdout);

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
                                         "--domain",
                                         std::to_string(domain),
                                         "--frames",
                                         std::to_string(frames),
                                         "--timeout",
                                         num(o->node_timeout)};
        for (auto& a : forwarded(o->run)) argv.push_back(std::move(a));
        const fs::path log = nodes / ("node_" + std::to_string(c.id) + ".log");
        fs::remove(log);
        pids.push_back(net::spawn(argv, log));
      }
      const auto res = net::supervise(pids, o->timeout, true);
      bool failed = false;
      for (size_t i = 0; i < res.size(); ++i) {
        const bool ok = res[i].finished && res[i].exit_code == 0;
        if (ok || (res[i].killed && failed)) continue;
        const fs::path log = nodes / ("node_" + std::to_string(netcfg.cameras[i].id) + ".log");
        std::fprintf(stderr, "netvmo launch: node of camera %d failed (%s): %s [%s]\n",
                     netcfg.cameras[i].id, net::describe(res[i]).c_str(), last_line(log).c_str(),
                     log.string().c_str());
        failed = true;
      }
      if (failed) {
        bool timed_out = false;
        for (const auto& r : res) timed_out |= r.killed;
        throw std::runtime_error(timed_out && o->timeout > 0
                                     ? "nodes failed or were stopped (timeout " + num(o->timeout) +
                                           " s); see " + nodes.string()
                                     : "a node failed; see " + nodes.string());
      }

      // Merge: the same result structure as run_images, then the same writers as `netvmo run`.
      auto result = net::merge_nodes(*provider, options, nodes, frames);
      json messages = json::object();
      for (const auto& c : netcfg.cameras) {
        const fs::path f = nodes / ("node_" + std::to_string(c.id) + ".json");
        std::ifstream in(f);
        json j;
        try {
          in >> j;
        } catch (const std::exception&) {
          throw InputError(f.string() + ": unreadable node statistics");
        }
        messages[std::to_string(c.id)] = j["messages"];
        for (const auto& w : j["warnings"]) result.warnings.push_back(w.get<std::string>());
        result.seconds = std::max(result.seconds, j["seconds"].get<double>());
      }
      io::write_file_atomic(dir / "messages.json", messages.dump(2) + "\n");
      if (!o->run.no_overlays) {
        pipeline::OverlayWriter overlays(dir, *provider);
        const size_t n = netcfg.cameras.size();
        for (int k = 0; k < frames; ++k) {
          std::vector<cv::Mat> images(n);
          for (size_t i = 0; i < n; ++i) {
            if (result.frames[static_cast<size_t>(k)][i].read_failed) continue;
            images[i] = provider->read(i, k);
          }
          overlays(k, images, result.frames[static_cast<size_t>(k)],
                   result.history[static_cast<size_t>(k)]);
        }
        overlays.finish();
      }
      for (size_t k = provider->warnings().size(); k < result.warnings.size(); ++k)
        std::fprintf(stderr, "warning: %s\n", result.warnings[k].c_str());
      const json s = pipeline::write_run_outputs(dir, *provider, options, result);
      if (!o->run.no_plots) {
        std::vector<int> ids;
        for (const auto& c : netcfg.cameras) ids.push_back(c.id);
        plot_run(dir, ids);
      }
      // Every node reads the one estimates topic: messages of non-neighbours are ignored (and
      // counted apart from those refused as malformed or out of order).
      std::printf("messages: camera    sent  received  dropped  late  non-neighbour  rejected\n");
      for (const auto& c : netcfg.cameras) {
        const auto& m = messages[std::to_string(c.id)];
        unsigned long long rejected = 0, foreign = 0;
        for (const auto& [k, v] : m["rejected"].items())
          (k == obs::to_string(obs::MessageVerdict::not_a_neighbour) ? foreign : rejected) +=
              v.get<unsigned long long>();
        std::printf("          %6d  %6llu  %8llu  %7llu  %4llu  %13llu  %8llu\n", c.id,
                    m["sent"].get<unsigned long long>(), m["received"].get<unsigned long long>(),
                    m["dropped"].get<unsigned long long>(), m["late"].get<unsigned long long>(),
                    foreign, rejected);
      }
      print_run_summary(s, dir);
      return 0;
    });
  });
}

}  // namespace netvmo::tools
