#include "netvmo/observer/graph.hpp"

#include <algorithm>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>

namespace netvmo::obs {

Graph::Graph(int n, const std::vector<Edge>& edges) : adj_(static_cast<size_t>(std::max(n, 0))) {
  if (n <= 0) throw std::invalid_argument("graph needs at least one node");
  for (const auto& [a, b] : edges) {
    if (a < 0 || b < 0 || a >= n || b >= n)
      throw std::invalid_argument("edge (" + std::to_string(a) + "," + std::to_string(b) +
                                  ") names a node outside 0.." + std::to_string(n - 1));
    if (a == b) throw std::invalid_argument("self loop at node " + std::to_string(a));
    auto& na = adj_[static_cast<size_t>(a)];
    if (std::find(na.begin(), na.end(), b) != na.end())
      throw std::invalid_argument("duplicated edge (" + std::to_string(a) + "," +
                                  std::to_string(b) + ")");
    na.push_back(b);
    adj_[static_cast<size_t>(b)].push_back(a);
    edges_.emplace_back(std::min(a, b), std::max(a, b));
  }
  for (auto& nb : adj_) std::sort(nb.begin(), nb.end());
}

int Graph::max_degree() const {
  int d = 0;
  for (const auto& nb : adj_) d = std::max(d, static_cast<int>(nb.size()));
  return d;
}

Eigen::SparseMatrix<double> Graph::laplacian() const {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(adj_.size() + 2 * edges_.size());
  for (int i = 0; i < size(); ++i) t.emplace_back(i, i, static_cast<double>(degree(i)));
  for (const auto& [a, b] : edges_) {
    t.emplace_back(a, b, -1.0);
    t.emplace_back(b, a, -1.0);
  }
  Eigen::SparseMatrix<double> L(size(), size());
  L.setFromTriplets(t.begin(), t.end());
  return L;
}

std::vector<int> Graph::hop_distances(int source) const {
  std::vector<int> dist(adj_.size(), -1);
  std::queue<int> q;
  dist[static_cast<size_t>(source)] = 0;
  q.push(source);
  while (!q.empty()) {
    const int u = q.front();
    q.pop();
    for (int v : neighbors(u)) {
      if (dist[static_cast<size_t>(v)] < 0) {
        dist[static_cast<size_t>(v)] = dist[static_cast<size_t>(u)] + 1;
        q.push(v);
      }
    }
  }
  return dist;
}

std::vector<std::vector<int>> Graph::components() const {
  std::vector<int> comp(adj_.size(), -1);
  std::vector<std::vector<int>> out;
  for (int s = 0; s < size(); ++s) {
    if (comp[static_cast<size_t>(s)] >= 0) continue;
    const auto d = hop_distances(s);
    std::vector<int> members;
    for (int v = 0; v < size(); ++v) {
      if (d[static_cast<size_t>(v)] >= 0) {
        comp[static_cast<size_t>(v)] = static_cast<int>(out.size());
        members.push_back(v);
      }
    }
    out.push_back(std::move(members));
  }
  return out;
}

int Graph::diameter() const {
  int diam = 0;
  for (int s = 0; s < size(); ++s) {
    for (int d : hop_distances(s)) {
      if (d < 0) throw std::logic_error("diameter of a disconnected graph");
      diam = std::max(diam, d);
    }
  }
  return diam;
}

namespace {

// Largest branch weight of a rooted tree given each node's branch (index into the root's
// neighbour list, -1 for the root): BFS inside each branch from its root child.
// Returns +inf if some branch is not connected.
double max_branch_weight(const Graph& g, int root, const std::vector<int>& branch_of,
                         std::vector<int>& depth_scratch) {
  const auto& kids = g.neighbors(root);
  std::fill(depth_scratch.begin(), depth_scratch.end(), -1);
  double worst = 0.0;
  std::vector<int> queue;
  queue.reserve(static_cast<size_t>(g.size()));
  std::vector<int> count(kids.size(), 0);
  for (int v = 0; v < g.size(); ++v)
    if (v != root) ++count[static_cast<size_t>(branch_of[static_cast<size_t>(v)])];
  for (size_t b = 0; b < kids.size(); ++b) {
    queue.clear();
    queue.push_back(kids[b]);
    depth_scratch[static_cast<size_t>(kids[b])] = 1;
    double w = 0.0;
    for (size_t h = 0; h < queue.size(); ++h) {
      const int u = queue[h];
      w += depth_scratch[static_cast<size_t>(u)];
      for (int v : g.neighbors(u)) {
        if (v == root || depth_scratch[static_cast<size_t>(v)] >= 0) continue;
        if (branch_of[static_cast<size_t>(v)] != static_cast<int>(b)) continue;
        depth_scratch[static_cast<size_t>(v)] = depth_scratch[static_cast<size_t>(u)] + 1;
        queue.push_back(v);
      }
    }
    if (static_cast<int>(queue.size()) != count[b]) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, w);
  }
  return worst;
}

// Exhaustive search over assignments of non-neighbours of the root to the root's children.
double exact_D(const Graph& g, int root) {
  const auto& kids = g.neighbors(root);
  std::vector<int> branch_of(static_cast<size_t>(g.size()), -1);
  std::vector<int> rest;
  for (size_t b = 0; b < kids.size(); ++b)
    branch_of[static_cast<size_t>(kids[b])] = static_cast<int>(b);
  for (int v = 0; v < g.size(); ++v)
    if (v != root && branch_of[static_cast<size_t>(v)] < 0) rest.push_back(v);
  std::vector<int> scratch(static_cast<size_t>(g.size()));
  const int k = static_cast<int>(kids.size());
  for (int v : rest) branch_of[static_cast<size_t>(v)] = 0;
  double best = std::numeric_limits<double>::infinity();
  while (true) {
    best = std::min(best, max_branch_weight(g, root, branch_of, scratch));
    size_t pos = 0;  // odometer increment over rest
    while (pos < rest.size()) {
      int& b = branch_of[static_cast<size_t>(rest[pos])];
      if (++b < k) break;
      b = 0;
      ++pos;
    }
    if (pos == rest.size()) break;
  }
  return best;
}

// Upper bound: a shortest-path tree in which each node joins the lightest branch among its
// possible BFS parents.
double heuristic_D(const Graph& g, int root) {
  const auto dist = g.hop_distances(root);
  std::vector<int> order(static_cast<size_t>(g.size()));
  for (int v = 0; v < g.size(); ++v) order[static_cast<size_t>(v)] = v;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return dist[static_cast<size_t>(a)] < dist[static_cast<size_t>(b)];
  });
  const auto& kids = g.neighbors(root);
  std::vector<int> branch_of(static_cast<size_t>(g.size()), -1);
  std::vector<double> weight(kids.size(), 0.0);
  for (size_t b = 0; b < kids.size(); ++b)
    branch_of[static_cast<size_t>(kids[b])] = static_cast<int>(b);
  for (int v : order) {
    const int dv = dist[static_cast<size_t>(v)];
    if (dv <= 0) continue;
    if (dv > 1) {
      int best_b = -1;
      for (int u : g.neighbors(v)) {
        if (dist[static_cast<size_t>(u)] != dv - 1) continue;
        const int b = branch_of[static_cast<size_t>(u)];
        if (best_b < 0 || weight[static_cast<size_t>(b)] < weight[static_cast<size_t>(best_b)])
          best_b = b;
      }
      branch_of[static_cast<size_t>(v)] = best_b;
    }
    weight[static_cast<size_t>(branch_of[static_cast<size_t>(v)])] += dv;
  }
  return weight.empty() ? 0.0 : *std::max_element(weight.begin(), weight.end());
}

}  // namespace

PaperW paper_W(const Graph& g, int max_exact_nodes) {
  if (!g.connected()) throw std::logic_error("W is defined for connected graphs only");
  PaperW out;
  out.value = std::numeric_limits<double>::infinity();
  const int n = g.size();
  if (n == 1) return PaperW{0.0, true, 0};
  out.exact = n <= max_exact_nodes;
  // The heuristic visits at most 64 roots spread over the nodes on large graphs.
  const int stride = out.exact || n <= 2000 ? 1 : n / 64;
  for (int r = 0; r < n; r += stride) {
    const double d = out.exact ? exact_D(g, r) : heuristic_D(g, r);
    if (d < out.value) {
      out.value = d;
      out.root = r;
    }
  }
  return out;
}

std::string describe_components(const std::vector<std::vector<int>>& comps,
                                const std::vector<int>& labels) {
  std::ostringstream os;
  for (size_t c = 0; c < comps.size(); ++c) {
    if (c) os << ' ';
    os << '{';
    for (size_t k = 0; k < comps[c].size(); ++k) {
      if (k) os << ',';
      const int v = comps[c][k];
      os << (static_cast<size_t>(v) < labels.size() ? labels[static_cast<size_t>(v)] : v);
    }
    os << '}';
  }
  return os.str();
}

}  // namespace netvmo::obs
