// The `netvmo` subcommands. Each add_<name> registers its subcommand with its options (all
// with defaults shown in --help) and a callback that stores the process exit code.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>

#include "netvmo/pipeline/net/live_camera.hpp"

namespace netvmo::tools {

/// Runs a command body; a thrown error becomes one line on stderr and exit code 1.
inline int guarded(const std::string& command, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "netvmo %s: error: %s\n", command.c_str(), e.what());
    return 1;
  }
}

/// Registers subcommand `name` with its one-line summary (the command list) and the footer of
/// its --help (what it writes).
inline CLI::App* add_command(CLI::App& app, const char* name, const char* summary,
                             const char* footer) {
  CLI::App* cmd = app.add_subcommand(name, summary);
  cmd->footer(footer);
  return cmd;
}

void add_simulate(CLI::App& app, int& exit_code);
void add_render(CLI::App& app, int& exit_code);
void add_detect(CLI::App& app, int& exit_code);
void add_run(CLI::App& app, int& exit_code);
void add_sweep(CLI::App& app, int& exit_code);
void add_demo(CLI::App& app, int& exit_code);
void add_bench(CLI::App& app, int& exit_code);
void add_node(CLI::App& app, int& exit_code);
void add_bag(CLI::App& app, int& exit_code);
void add_play(CLI::App& app, int& exit_code);
void add_launch(CLI::App& app, int& exit_code);
void add_merge(CLI::App& app, int& exit_code);  // cmd_launch.cpp
void add_security(CLI::App& app, int& exit_code);
void add_calibrate(CLI::App& app, int& exit_code);
void add_trajectories(CLI::App& app, int& exit_code);
/// The async options shared by `node` and `launch` (cmd_node.cpp).
void add_async_options(CLI::App& cmd, double& speed, double& stale, double& drop, double& delay,
                       std::uint64_t& seed);
/// --duration, --idle and --lag of a live run (node, launch) into `live`; --live itself into
/// `on`.
void add_live_options(CLI::App& cmd, bool& on, net::LiveSettings& live);

}  // namespace netvmo::tools
