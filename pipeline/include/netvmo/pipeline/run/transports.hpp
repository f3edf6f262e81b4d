// The registry of transports a run can choose by name (ImageRunSettings::transport, the command
// line's --transport): how the cameras' estimates travel between the per-camera observers.
//
// Adding a transport: a class implementing obs::Transport (observer/transport.hpp) and a
// TransportKind that makes it, in their own file under pipeline/src/run/, and one line in the
// table of pipeline/src/run/transports.cpp. The kind declares its own parameters: the command
// line offers each as --<name> with its help and range, summaries record them, and
// make_transport checks them, so nothing else changes.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/registry.hpp"
#include "netvmo/observer/transport.hpp"

namespace netvmo::run {

/// One parameter of a transport kind.
struct TransportParameter {
  std::string name;  ///< the key in TransportSettings::values and the option --<name>
  std::string help;  ///< one line for --help
  double default_value = 0.0;
  double min = 0.0, max = 0.0;  ///< the accepted range, both ends included
  bool integer = false;         ///< a count or a seed: whole numbers only (up to 2^53)
};

/// Which transport, and its parameters. Defaults: direct in-process delivery.
struct TransportSettings {
  std::string kind = "in-process";  ///< a registered name (transport_kinds())
  /// The kind's parameters by name (TransportKind::parameters()); one not given takes its
  /// default. Values of parameters another kind declares are ignored.
  std::map<std::string, double> values;
};

class TransportKind {
 public:
  virtual ~TransportKind() = default;
  virtual std::string_view name() const = 0;
  /// One line for --help.
  virtual std::string_view description() const = 0;
  /// The parameters it reads (none by default).
  virtual std::vector<TransportParameter> parameters() const { return {}; }
  /// A transport for the graph; `values` holds every parameter of parameters(), checked.
  virtual std::unique_ptr<obs::Transport> make(
      const obs::Graph& graph, const std::map<std::string, double>& values) const = 0;
};

/// The registry (observer/registry.hpp): every transport kind, in the order help texts list
/// them (the default first).
const obs::Registry<TransportKind>& transport_kinds();
/// A transport of the named kind for the graph. Throws InputError for an unknown kind (naming
/// the known ones) or a parameter outside its range (naming it and the range).
std::unique_ptr<obs::Transport> make_transport(const TransportSettings& s, const obs::Graph& graph);
/// The settings' parameters of their kind, defaults filled in and checked (as make_transport):
/// what a summary records.
std::map<std::string, double> transport_values(const TransportSettings& s);

}  // namespace netvmo::run
