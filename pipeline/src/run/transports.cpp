// The transport registry. Adding a transport: a file in this folder that defines a function
// returning its TransportKind, and one line in the table below (with its declaration).
#include "netvmo/pipeline/run/transports.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::run {

namespace transports {
const TransportKind& lossy();  // lossy_transport.cpp

namespace {
class InProcess final : public TransportKind {
 public:
  std::string_view name() const override { return "in-process"; }
  std::string_view description() const override {
    return "every neighbour's estimate, every round, in this process (the default)";
  }
  std::unique_ptr<obs::Transport> make(const obs::Graph& g,
                                       const std::map<std::string, double>&) const override {
    return std::make_unique<obs::InProcessTransport>(g);
  }
};

const TransportKind& in_process() {
  static const InProcess kind;
  return kind;
}
}  // namespace
}  // namespace transports

const obs::Registry<TransportKind>& transport_kinds() {
  static const obs::Registry<TransportKind> table{"transport",
                                                  {
                                                      &transports::in_process(),
                                                      &transports::lossy(),
                                                  }};
  return table;
}

namespace {
const TransportKind& find_kind(const std::string& name) {
  try {
    return transport_kinds().find(name);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("transport: ") + e.what());
  }
}
}  // namespace

std::map<std::string, double> transport_values(const TransportSettings& s) {
  const TransportKind& kind = find_kind(s.kind);
  std::map<std::string, double> values;
  for (const auto& p : kind.parameters()) {
    const auto given = s.values.find(p.name);
    const double v = given == s.values.end() ? p.default_value : given->second;
    if (!(v >= p.min && v <= p.max) || (p.integer && v != std::floor(v))) {
      std::ostringstream m;
      m << "transport " << kind.name() << ": " << p.name << " = " << v << " is outside [" << p.min
        << ", " << p.max << "]" << (p.integer ? " or not a whole number" : "");
      throw InputError(m.str());
    }
    values[p.name] = v;
  }
  return values;
}

std::unique_ptr<obs::Transport> make_transport(const TransportSettings& s,
                                               const obs::Graph& graph) {
  return find_kind(s.kind).make(graph, transport_values(s));
}

}  // namespace netvmo::run
