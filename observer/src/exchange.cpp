#include "netvmo/observer/exchange.hpp"

#include <algorithm>

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

namespace {

// How many of c's neighbours' latest estimates it holds are initialised.
int heard(const CameraObserver& c) {
  const auto& latest = c.latest();
  return static_cast<int>(std::count_if(latest.begin(), latest.end(),
                                        [](const auto& m) { return m && m->initialized; }));
}

}  // namespace

bool JoinHold::may_step(const CameraObserver& c, double now) const {
  return !held || now >= until || heard(c) == static_cast<int>(c.neighbours().size());
}

bool JoinHold::release(const CameraObserver& c, double now) {
  if (!held) return false;
  if (!c.initialized()) {
    if (now < until) return false;
    if (heard(c) > 0 && !stepped_past_until) {
      stepped_past_until = true;  // one step from those heard first (the caller steps next)
      return false;
    }
  }
  held = false;
  return true;
}

}  // namespace netvmo::obs
