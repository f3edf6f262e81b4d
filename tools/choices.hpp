// Command-line choices read from the libraries' registries, so that a new error model or
// transport appears in every command's checks and --help without an edit here.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/run/transports.hpp"

namespace netvmo::tools {

enum class ErrorModelUse { images, simulation };

/// Adds --error, restricted to the registered error models usable for `use`, with one help line
/// per model.
CLI::Option* add_error_model_option(CLI::App& cmd, std::string& value, ErrorModelUse use);

/// Adds --estimator, restricted to the registered estimators, with one help line each.
CLI::Option* add_estimator_option(CLI::App& cmd, std::string& value);

/// Adds --transport (the registered kinds, one help line each), --drop and --seed.
void add_transport_options(CLI::App& cmd, run::TransportSettings& s);

/// Adds how the front end searches each camera's frames: --no-track, --acquire-every,
/// --full-res-below, --no-shadow-retry (defaults: frontend::TrackingSettings).
void add_search_options(CLI::App& cmd, frontend::TrackingSettings& t);
/// The same settings as arguments for add_search_options (a launched node's command line).
std::vector<std::string> search_arguments(const frontend::TrackingSettings& t);

}  // namespace netvmo::tools
