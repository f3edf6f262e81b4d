#include "netvmo/observer/exchange.hpp"

namespace netvmo::obs {

void send_estimate(CameraObserver& c, Transport& t, double stamp) {
  t.send(c.publish(stamp));
}

TakeReport take_estimates(CameraObserver& c, Transport& t, std::vector<EstimateMessage>& inbox,
                          const std::optional<Staleness>& stale) {
  TakeReport report;
  t.receive(c.index(), inbox);
  report.received = static_cast<int>(inbox.size());
  for (const auto& m : inbox) c.receive(m);
  if (stale) {
    const auto& latest = c.latest();
    for (size_t a = 0; a < latest.size(); ++a)
      if (latest[a] && stale->now - latest[a]->stamp > stale->bound) {
        c.forget(c.neighbours()[a]);
        ++report.forgotten;
      }
  }
  return report;
}

}  // namespace netvmo::obs
