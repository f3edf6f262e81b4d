// Command-line choices read from the libraries' registries, so that a new error model or
// transport appears in every command's checks and --help without an edit here.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

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

}  // namespace netvmo::tools
