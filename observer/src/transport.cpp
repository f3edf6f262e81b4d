#include "netvmo/observer/transport.hpp"

namespace netvmo::obs {

InProcessTransport::InProcessTransport(Graph graph)
    : graph_(std::move(graph)),
      sent_(static_cast<size_t>(graph_.size())),
      has_sent_(static_cast<size_t>(graph_.size()), false) {}

void InProcessTransport::send(const EstimateMessage& m) {
  const auto s = static_cast<size_t>(m.sender);
  if (m.sender < 0 || s >= sent_.size()) return;  // not a camera of this network: dropped
  sent_[s] = m;
  has_sent_[s] = true;
}

void InProcessTransport::receive(int receiver, std::vector<EstimateMessage>& out) {
  out.clear();
  for (int j : graph_.neighbors(receiver))
    if (has_sent_[static_cast<size_t>(j)]) out.push_back(sent_[static_cast<size_t>(j)]);
}

}  // namespace netvmo::obs
