// The transport registry. Adding a transport: a file in this folder that defines a function
// returning its TransportKind, and one line in the table below (with its declaration).
#include "netvmo/pipeline/run/transports.hpp"

#include "netvmo/pipeline/error.hpp"

namespace netvmo::run {

namespace transports {
const TransportKind& lossy();  // lossy_transport.cpp

namespace {
const TransportKind& in_process() {
  static const TransportKind kind{
      "in-process", "every neighbour's estimate, every round, in this process (the default)",
      [](const obs::Graph& g, const TransportSettings&) -> std::unique_ptr<obs::Transport> {
        return std::make_unique<obs::InProcessTransport>(g);
      }};
  return kind;
}
}  // namespace
}  // namespace transports

const std::vector<const TransportKind*>& transport_kinds() {
  static const std::vector<const TransportKind*> table{
      &transports::in_process(),
      &transports::lossy(),
  };
  return table;
}

std::unique_ptr<obs::Transport> make_transport(const TransportSettings& s,
                                               const obs::Graph& graph) {
  std::string known;
  for (const auto* k : transport_kinds()) {
    if (s.kind == k->name) return k->make(graph, s);
    known += std::string(known.empty() ? "" : ", ") + k->name;
  }
  throw InputError("transport: unknown kind '" + s.kind + "' (" + known + ")");
}

}  // namespace netvmo::run
