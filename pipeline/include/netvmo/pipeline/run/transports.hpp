// The registry of transports a run can choose by name (ImageRunOptions::transport, the command
// line's --transport): how the cameras' estimates travel between the per-camera observers.
//
// Adding a transport: a class implementing obs::Transport (observer/transport.hpp) in its own
// file under pipeline/src/run/, a function there returning its TransportKind, and one line in
// the table of pipeline/src/run/transports.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/transport.hpp"

namespace netvmo::run {

/// Which transport, and its settings. Defaults: direct in-process delivery.
struct TransportSettings {
  std::string kind = "in-process";  ///< a registered name (transport_kinds())
  double drop = 0.0;                ///< "lossy": probability that a message is lost, in [0, 1)
  std::uint64_t seed = 1;           ///< "lossy": seed of the losses (runs repeat)
};

struct TransportKind {
  const char* name;
  const char* description;  ///< one line for --help
  std::unique_ptr<obs::Transport> (*make)(const obs::Graph& graph, const TransportSettings& s);
};

/// The registry: every transport kind, in the order help texts list them.
const std::vector<const TransportKind*>& transport_kinds();
/// A transport of the named kind for the graph. Throws InputError for an unknown kind (naming
/// the known ones) or settings out of range.
std::unique_ptr<obs::Transport> make_transport(const TransportSettings& s, const obs::Graph& graph);

}  // namespace netvmo::run
