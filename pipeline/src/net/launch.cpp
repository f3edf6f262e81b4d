#include "netvmo/pipeline/net/launch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "netvmo/observer/estimate_message.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string last_line(const fs::path& log) {
  std::ifstream f(log);
  std::string line, last;
  while (std::getline(f, line))
    if (!line.empty()) last = line;
  return last;
}

}  // namespace

NodeKill parse_node_kill(const std::string& spec, double restart_after,
                         const io::NetworkConfig& net) {
  const auto at = spec.find('@');
  int id = -1;
  double t = -1;
  if (at != std::string::npos) {
    id = io::parse_int(spec.substr(0, at)).value_or(-1);
    t = io::parse_finite(spec.substr(at + 1)).value_or(-1);
  }
  if (at == std::string::npos || net.index_of(id) < 0 || !(t >= 0))
    throw InputError("--kill " + spec + ": expected ID@SECONDS with a camera id of " + net.source);
  return {id, t, restart_after};
}

std::map<int, double> parse_clock_offsets(const std::string& spec, const io::NetworkConfig& net) {
  std::map<int, double> out;
  std::stringstream in(spec);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto colon = item.find(':');
    int id = -1;
    double s = NAN;
    if (colon != std::string::npos) {
      id = io::parse_int(item.substr(0, colon)).value_or(-1);
      s = io::parse_finite(item.substr(colon + 1)).value_or(NAN);
    }
    if (colon == std::string::npos || net.index_of(id) < 0 || !std::isfinite(s) || out.count(id))
      throw InputError("--clock-offsets " + spec + ": '" + item +
                       "': expected ID:SECONDS, each camera of " + net.source + " at most once");
    out[id] = s;
  }
  return out;
}

std::vector<std::string> node_argv(const LaunchSettings& s, int camera_id,
                                   const fs::path& nodes_dir) {
  std::vector<std::string> argv = {s.exe.string(),
                                   "node",
                                   s.dataset.string(),
                                   "--camera",
                                   std::to_string(camera_id),
                                   "--out",
                                   nodes_dir.string(),
                                   "--in-place",
                                   "--domain",
                                   std::to_string(s.domain),
                                   "--timeout",
                                   io::exact_text(s.node_timeout)};
  if (s.frames > 0 || !s.live)
    for (auto a : {std::string("--frames"), std::to_string(s.frames)}) argv.push_back(a);
  if (!s.security.empty())
    for (auto a : {std::string("--security"), s.security.string()}) argv.push_back(a);
  if (s.ros_wait_readers > 0)
    for (auto a : {std::string("--ros-wait-readers"), std::to_string(s.ros_wait_readers)})
      argv.push_back(a);
  if (s.live)
    for (auto a :
         {std::string("--live"), std::string("--duration"), io::exact_text(s.live->duration_s),
          std::string("--idle"), io::exact_text(s.live->idle_s), std::string("--lag"),
          io::exact_text(s.live->lag_s)})
      argv.push_back(a);
  for (const auto& a : s.run_arguments) argv.push_back(a);
  if (s.async)
    for (auto a : {std::string("--mode"), std::string("async"), std::string("--speed"),
                   io::exact_text(s.speed), std::string("--stale"), io::exact_text(s.stale),
                   std::string("--drop"), io::exact_text(s.drop), std::string("--delay"),
                   io::exact_text(s.delay), std::string("--seed"), std::to_string(s.seed),
                   std::string("--start-file"), (nodes_dir / "start.txt").string()})
      argv.push_back(a);
  if (const auto c = s.clock_offsets.find(camera_id); c != s.clock_offsets.end())
    for (auto a : {std::string("--clock-offset"), io::exact_text(c->second)}) argv.push_back(a);
  return argv;
}

LaunchOutcome run_launch(const io::NetworkConfig& net, const LaunchSettings& s,
                         const fs::path& nodes_dir) {
  const fs::path start_file = nodes_dir / "start.txt";  // async: the common start
  fs::remove(start_file);
  std::fflush(stdout);  // before the children inherit the buffer
  KillPlan plan;
  if (s.kill) {
    plan.index = static_cast<size_t>(net.index_of(s.kill->camera_id));
    plan.kill_at = s.kill->at;  // after the common start (made relative to it below)
    plan.restart_after = s.kill->restart_after;
  }
  std::vector<pid_t> pids;
  for (const auto& c : net.cameras) {
    const auto argv = node_argv(s, c.id, nodes_dir);
    const fs::path log = node_files(nodes_dir, c.id).log;
    if (s.kill && pids.size() == plan.index) {
      plan.argv = argv;
      plan.argv.push_back("--resume");  // keeps the rows it finished before the kill
      plan.log = log;
    }
    pids.push_back(spawn(argv, log));
  }
  LaunchOutcome outcome;
  if (s.async) {
    // The common start, once every node is ready (or one has ended, or --node-timeout has
    // passed: then supervise reports it); printed for the record.
    const double give_up = epoch_seconds() + s.node_timeout;
    for (;;) {
      bool ready = true, ended = false;
      for (size_t i = 0; i < pids.size(); ++i) {
        ready = ready && fs::exists(node_ready_file(start_file, net.cameras[i].id));
        ended = ended || has_exited(pids[i]);
      }
      if (ready || ended || epoch_seconds() > give_up) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    outcome.start_epoch = epoch_seconds() + kLaunchStartMargin;
    io::write_file_atomic(start_file, io::exact_text(outcome.start_epoch) + "\n");
    plan.kill_at += outcome.start_epoch - epoch_seconds();  // supervision starts now
    if (s.live)
      std::printf(
          "netvmo launch: live, every node ready: waiting for images on the cameras' "
          "topics (each run ends %g s after its camera's last image)\n",
          s.live->idle_s);
    else
      std::printf(
          "netvmo launch: async, speed %g, staleness %g s, drop %g, delay %g ms, seed %llu, "
          "start at %.3f (epoch)\n",
          s.speed, s.stale, s.drop, s.delay, static_cast<unsigned long long>(s.seed),
          outcome.start_epoch);
    std::fflush(stdout);
  }
  outcome.nodes = supervise(pids, s.timeout, true, s.kill ? &plan : nullptr);
  if (s.kill) {  // the injected fault, in wall and camera time
    const auto& r = outcome.nodes[plan.index];
    const auto cam_time = [&](double epoch) { return (epoch - outcome.start_epoch) * s.speed; };
    json events = json::object();
    events["camera"] = s.kill->camera_id;
    events["start_epoch"] = outcome.start_epoch;
    events["speed"] = s.speed;
    if (r.kill_epoch > 0)
      events["kill"] = {{"epoch", r.kill_epoch}, {"camera_time", cam_time(r.kill_epoch)}};
    if (r.restart_epoch > 0)
      events["restart"] = {{"epoch", r.restart_epoch}, {"camera_time", cam_time(r.restart_epoch)}};
    io::write_file_atomic(nodes_dir / "events.json", events.dump(2) + "\n");
  }
  return outcome;
}

void check_launch(const LaunchOutcome& outcome, const io::NetworkConfig& net,
                  const LaunchSettings& s, const fs::path& nodes_dir,
                  const fs::path& kept_nodes_dir, const std::function<fs::path()>& keep_failed) {
  // Report the nodes that failed on their own first; the others were stopped because of them,
  // or by the timeout.
  std::vector<int> stopped;
  bool failed = false;
  for (size_t i = 0; i < outcome.nodes.size(); ++i) {
    const auto& r = outcome.nodes[i];
    const int id = net.cameras[i].id;
    if ((r.finished && r.exit_code == 0) || r.planned_kill) continue;
    if (r.killed) {
      stopped.push_back(id);
      continue;
    }
    const fs::path log = node_files(nodes_dir, id).log;
    std::fprintf(stderr, "netvmo launch: node of camera %d failed (%s): %s [%s]\n", id,
                 describe(r).c_str(), last_line(log).c_str(),
                 (kept_nodes_dir / log.filename()).string().c_str());
    failed = true;
  }
  if (failed) throw std::runtime_error("a node failed; see " + (keep_failed() / "nodes").string());
  if (!stopped.empty()) {
    std::string ids;
    for (int id : stopped) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    throw std::runtime_error("timeout after " + io::exact_text(s.timeout) +
                             " s: stopped the nodes of cameras " + ids + "; see " +
                             (keep_failed() / "nodes").string());
  }
}

json read_node_json(const fs::path& f) {
  if (!fs::exists(f)) throw InputError(f.string() + ": node statistics not found");
  std::ifstream in(f);
  json j;
  try {
    in >> j;
  } catch (const std::exception&) {
    throw InputError(f.string() + ": unreadable node statistics");
  }
  // What the merge reads of every node (node.cpp writes them all; gathered files may not have).
  if (!j.is_object()) throw InputError(f.string() + ": node statistics are not a JSON object");
  const auto require = [&](const char* key, bool (json::*is)() const noexcept, const char* what) {
    if (!j.contains(key) || !(j.at(key).*is)())
      throw InputError(f.string() + ": " + key + ": missing or not " + what +
                       " (node statistics as netvmo node writes them)");
  };
  require("mode", &json::is_string, "a string");
  require("messages", &json::is_object, "an object");
  require("warnings", &json::is_array, "an array");
  require("seconds", &json::is_number, "a number");
  for (const auto& w : j.at("warnings"))
    if (!w.is_string())
      throw InputError(f.string() + ": warnings: " + w.dump() + " is not a string");
  return j;
}

namespace {

// The nodes' reports of their neighbours' clocks (node_<id>.json "clock"), aligned on the first
// camera's clock.
ClockAlignment node_clocks(const io::NetworkConfig& net, const std::vector<json>& node_json,
                           const fs::path& nodes_dir) {
  std::vector<ClockLink> links;
  for (size_t i = 0; i < node_json.size(); ++i) {
    const json& j = node_json[i];
    if (j.is_null() || !j.contains("clock")) continue;
    const fs::path f = node_files(nodes_dir, net.cameras[i].id).json;
    try {
      for (const auto& e : j.at("clock").at("neighbours")) {
        ClockLink l;
        l.by = static_cast<int>(i);
        l.of = net.index_of(e.at("camera").get<int>());
        if (l.of < 0)
          throw InputError(f.string() + ": clock: camera " + e.at("camera").dump() + " is not in " +
                           net.source);
        l.offset.offset_s = e.at("offset_s").get<double>();
        l.offset.delay_s = e.at("delay_s").is_null() ? INFINITY : e.at("delay_s").get<double>();
        l.offset.round_trips = e.at("round_trips").get<std::uint64_t>();
        links.push_back(l);
      }
    } catch (const json::exception& e) {
      throw InputError(f.string() + ": clock: " + e.what());
    }
  }
  return align_clocks(net.cameras.size(), 0, links);
}

json exchange_json(const io::NetworkConfig& net, const std::vector<json>& node_json) {
  json nodes = json::object();
  std::vector<double> medians, p99s, firsts, taken, discovery;
  for (size_t i = 0; i < node_json.size(); ++i) {
    const json& j = node_json[i];
    if (j.is_null() || !j.contains("timing")) continue;
    json t = j["timing"];
    const double rounds = t.value("rounds", 0.0);
    const double received = j.at("messages").value("received", 0.0);
    t["taken_per_round"] = rounds > 0 ? json(received / rounds) : json(nullptr);
    nodes[std::to_string(net.cameras[i].id)] = t;
    discovery.push_back(t.value("discovery_s", 0.0));
    medians.push_back(t.value("round_median_us", 0.0));
    p99s.push_back(t.value("round_p99_us", 0.0));
    firsts.push_back(t.value("first_round_median_us", 0.0));
    if (rounds > 0) taken.push_back(received / rounds);
  }
  json all = json::object();
  if (!medians.empty()) {
    const auto median = [](std::vector<double> m) {
      std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(m.size() / 2), m.end());
      return m[m.size() / 2];
    };
    double sum = 0.0;
    for (double v : taken) sum += v;
    all = {{"nodes", medians.size()},
           {"discovery_max_s", *std::max_element(discovery.begin(), discovery.end())},
           {"round_median_us", median(medians)},
           {"round_p99_max_us", *std::max_element(p99s.begin(), p99s.end())},
           {"first_round_median_us", median(firsts)},
           {"taken_per_round_mean",
            taken.empty() ? json(nullptr) : json(sum / static_cast<double>(taken.size()))}};
  }
  return {{"all", all}, {"nodes", nodes}};
}

json clocks_json(const ClockAlignment& a, const io::NetworkConfig& net) {
  json cams = json::array();
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    json c = {{"camera", net.cameras[i].id}};
    c["offset_s"] = a.offset_s[i] ? json(*a.offset_s[i]) : json(nullptr);
    c["bound_s"] = a.bound_s[i] ? json(*a.bound_s[i]) : json(nullptr);
    c["correction_s"] = a.correction_s[i];
    cams.push_back(c);
  }
  return {{"reference_camera", net.cameras[static_cast<size_t>(a.reference)].id},
          {"cameras", cams}};
}

}  // namespace

MergedRun merge_run_outputs(sources::NetworkSource& source, const run::ImageRunSettings& options,
                            const fs::path& nodes_dir, const fs::path& dir, int frames,
                            bool allow_gaps, const run::OverlaySettings* overlays) {
  const auto& netcfg = source.network();
  MergedRun merged;
  merged.messages = json::object();
  std::vector<json> node_json;  // by camera (null: none)
  bool async = false;
  for (const auto& c : netcfg.cameras) {
    const fs::path f = node_files(nodes_dir, c.id).json;
    if (allow_gaps && !fs::exists(f)) {  // killed and not restarted: it never finished
      merged.messages[std::to_string(c.id)] = nullptr;
      node_json.emplace_back();
      continue;
    }
    node_json.push_back(read_node_json(f));
    merged.messages[std::to_string(c.id)] = node_json.back()["messages"];
    async = async || node_json.back()["mode"] == "async";
  }
  // Async nodes may run on hosts whose clocks disagree: their rows go onto the first camera's
  // clock (ClockSync, align_clocks); lock-step runs on one clock by construction.
  std::optional<ClockAlignment> clocks;
  if (async) clocks = node_clocks(netcfg, node_json, nodes_dir);
  auto result = merge_nodes(source, options, nodes_dir, frames, allow_gaps,
                            clocks ? clocks->correction_s : std::vector<double>{});
  for (const auto& j : node_json) {
    if (j.is_null()) continue;
    for (const auto& w : j["warnings"]) result.warnings.push_back(w.get<std::string>());
    result.seconds = std::max(result.seconds, j["seconds"].get<double>());
  }
  merged.exchange = exchange_json(netcfg, node_json);
  io::ensure_directory(dir);
  io::write_file_atomic(dir / "messages.json", merged.messages.dump(2) + "\n");
  io::write_file_atomic(dir / "exchange.json", merged.exchange.dump(2) + "\n");
  if (clocks) {
    io::write_file_atomic(dir / "clocks.json", clocks_json(*clocks, netcfg).dump(2) + "\n");
    for (size_t i = 0; i < netcfg.cameras.size(); ++i)
      if (!clocks->offset_s[i])
        result.warnings.push_back(
            "camera " + std::to_string(netcfg.cameras[i].id) + ": its clock's offset to camera " +
            std::to_string(netcfg.cameras[static_cast<size_t>(clocks->reference)].id) +
            "'s is unknown (no chain of round trips of estimates joins them); its rows stay on "
            "its own clock");
  }
  if (overlays) {
    run::OverlayWriter writer(dir, source, *overlays);
    const size_t n = netcfg.cameras.size();
    for (int k = 0; k < frames; ++k) {
      std::vector<cv::Mat> images(n);
      for (size_t i = 0; i < n; ++i) {
        if (result.frames[static_cast<size_t>(k)][i].read_failed) continue;
        // Cameras on their own clocks: the image each camera held at this grid time.
        const int own =
            result.source_frames.empty() ? k : result.source_frames[static_cast<size_t>(k)][i];
        if (own >= 0) images[i] = source.read(i, own);
      }
      writer(k, images, {result.frames[static_cast<size_t>(k)]},
             {&result.history[static_cast<size_t>(k)]});
    }
    writer.finish();
  }
  for (size_t k = source.warnings().size(); k < result.warnings.size(); ++k)
    std::fprintf(stderr, "warning: %s\n", result.warnings[k].c_str());
  merged.summary = run::write_run_outputs(dir, source, options, result);
  return merged;
}

std::string exchange_line(const json& exchange) {
  const json& a = exchange.at("all");
  if (a.empty()) return "exchange: no node timing\n";
  char line[400];
  std::snprintf(
      line, sizeof line,
      "exchange: %d nodes, discovery %.3f s (slowest), round %.1f us (median of the "
      "nodes' medians), p99 %.1f us (largest), a frame's first round %.1f us (with "
      "the neighbours' front ends), %.2f estimates taken per round\n",
      a["nodes"].get<int>(), a["discovery_max_s"].get<double>(), a["round_median_us"].get<double>(),
      a["round_p99_max_us"].get<double>(), a["first_round_median_us"].get<double>(),
      a["taken_per_round_mean"].is_null() ? 0.0 : a["taken_per_round_mean"].get<double>());
  return line;
}

std::string message_table(const json& messages, const io::NetworkConfig& net) {
  // Every node reads its neighbours' estimate topics: a sample there under another sender's
  // index (dropped by the transport) or from a non-neighbour (refused by the observer) is
  // foreign, counted apart from those refused as malformed or out of order.
  std::string t = "messages: camera    sent  received  dropped  late  foreign  rejected\n";
  char line[200];
  for (const auto& c : net.cameras) {
    const auto& m = messages[std::to_string(c.id)];
    if (m.is_null()) {
      std::snprintf(line, sizeof line, "          %6d  (killed, no statistics)\n", c.id);
      t += line;
      continue;
    }
    unsigned long long rejected = 0, foreign = m.value("foreign", 0ULL);
    for (const auto& [k, v] : m["rejected"].items())
      (k == obs::to_string(obs::MessageVerdict::not_a_neighbour) ? foreign : rejected) +=
          v.get<unsigned long long>();
    std::snprintf(line, sizeof line, "          %6d  %6llu  %8llu  %7llu  %4llu  %7llu  %8llu\n",
                  c.id, m["sent"].get<unsigned long long>(),
                  m["received"].get<unsigned long long>(), m["dropped"].get<unsigned long long>(),
                  m["late"].get<unsigned long long>(), foreign, rejected);
    t += line;
  }
  return t;
}

}  // namespace netvmo::net
