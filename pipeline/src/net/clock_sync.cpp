#include "netvmo/pipeline/net/clock_sync.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace netvmo::net {

bool ClockOffset::round_trip() const {
  return std::isfinite(delay_s);
}

ClockSync::ClockSync(int self, std::vector<int> neighbours)
    : self_(self), neighbours_(std::move(neighbours)), links_(neighbours_.size()) {}

void ClockSync::taken(int from, double sent, double taken, const ClockEcho* echoes,
                      std::size_t count) {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), from);
  if (it == neighbours_.end()) return;
  Link& l = links_[static_cast<std::size_t>(it - neighbours_.begin())];
  // One way: taken = sent - theta + d with d >= 0, so sent - taken <= theta.
  const double one_way = sent - taken;
  if (!l.heard || one_way > l.one_way) l.one_way = one_way;
  if (!l.heard) {
    l.heard = true;
    l.best.delay_s = std::numeric_limits<double>::infinity();
    l.best.offset_s = one_way;
  }
  // The echo of this camera's own message closes a round trip (t1, t2, t3 = sent, t4 = taken).
  for (std::size_t e = 0; e < count; ++e) {
    if (echoes[e].camera != self_) continue;
    const double t1 = echoes[e].sent, t2 = echoes[e].received;
    const double delay = (taken - t1) - (sent - t2);
    if (!(delay >= 0.0) || !std::isfinite(delay)) {
      ++ignored_;
      break;
    }
    ++l.best.round_trips;
    if (delay <= l.best.delay_s) {
      l.best.delay_s = delay;
      l.best.offset_s = ((t2 - t1) + (sent - taken)) / 2.0;
    }
    break;
  }
  if (!l.best.round_trip()) l.best.offset_s = l.one_way;
  // What this camera echoes to `from` next.
  const auto e = std::find_if(echoes_.begin(), echoes_.end(),
                              [from](const ClockEcho& x) { return x.camera == from; });
  if (e == echoes_.end())
    echoes_.push_back({from, sent, taken});
  else
    *e = {from, sent, taken};
}

std::optional<ClockOffset> ClockSync::offset(int j) const {
  const auto it = std::find(neighbours_.begin(), neighbours_.end(), j);
  if (it == neighbours_.end()) return std::nullopt;
  const Link& l = links_[static_cast<std::size_t>(it - neighbours_.begin())];
  if (!l.heard) return std::nullopt;
  return l.best;
}

double ClockSync::to_own_clock(int j, double stamp) const {
  const auto o = offset(j);
  return o ? stamp - o->offset_s : stamp;
}

ClockAlignment align_clocks(std::size_t cameras, int reference,
                            const std::vector<ClockLink>& links) {
  // Each undirected edge's report of least delay, as clock_b - clock_a for a < b.
  struct Edge {
    int a, b;
    double theta, bound;
  };
  std::vector<Edge> edges;
  const auto valid = [cameras](int i) { return i >= 0 && static_cast<std::size_t>(i) < cameras; };
  for (const auto& l : links) {
    if (!l.offset.round_trip() || !valid(l.by) || !valid(l.of) || l.by == l.of) continue;
    const int a = std::min(l.by, l.of), b = std::max(l.by, l.of);
    const double theta = l.by == a ? l.offset.offset_s : -l.offset.offset_s;
    const double bound = l.offset.delay_s / 2.0;
    auto e = std::find_if(edges.begin(), edges.end(),
                          [&](const Edge& x) { return x.a == a && x.b == b; });
    if (e == edges.end())
      edges.push_back({a, b, theta, bound});
    else if (bound < e->bound)
      *e = {a, b, theta, bound};
  }
  ClockAlignment out;
  out.reference = reference;
  out.offset_s.assign(cameras, std::nullopt);
  out.bound_s.assign(cameras, std::nullopt);
  out.correction_s.assign(cameras, 0.0);
  if (!valid(reference)) return out;
  // Dijkstra from the reference over the edges' bounds.
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  out.offset_s[static_cast<std::size_t>(reference)] = 0.0;
  out.bound_s[static_cast<std::size_t>(reference)] = 0.0;
  queue.push({0.0, reference});
  std::vector<bool> done(cameras, false);
  while (!queue.empty()) {
    const auto [b, i] = queue.top();
    queue.pop();
    if (done[static_cast<std::size_t>(i)]) continue;
    done[static_cast<std::size_t>(i)] = true;
    const double x = *out.offset_s[static_cast<std::size_t>(i)];
    for (const auto& e : edges) {
      if (e.a != i && e.b != i) continue;
      const int j = e.a == i ? e.b : e.a;
      const double theta = e.a == i ? e.theta : -e.theta;  // clock_j - clock_i
      auto& bj = out.bound_s[static_cast<std::size_t>(j)];
      if (done[static_cast<std::size_t>(j)] || (bj && *bj <= b + e.bound)) continue;
      bj = b + e.bound;
      out.offset_s[static_cast<std::size_t>(j)] = x + theta;
      queue.push({*bj, j});
    }
  }
  for (std::size_t i = 0; i < cameras; ++i)
    if (out.offset_s[i] && std::abs(*out.offset_s[i]) > *out.bound_s[i])
      out.correction_s[i] = *out.offset_s[i];
  return out;
}

}  // namespace netvmo::net
