// The communication graph G = (V, E) of the camera network and its quantities used by the
// paper: neighbour sets (eq:ni), Laplacian, connectivity (Assumption 1), diameter and W
// (eqn:defD).
#pragma once

#include <Eigen/SparseCore>
#include <string>
#include <utility>
#include <vector>

namespace netvmo::obs {

/// Fixed, undirected graph on nodes 0..n-1 (camera indices, not user-facing ids).
class Graph {
 public:
  using Edge = std::pair<int, int>;

  /// Throws std::invalid_argument on self loops, out-of-range nodes or duplicated edges.
  Graph(int n, const std::vector<Edge>& edges);

  int size() const { return static_cast<int>(adj_.size()); }
  const std::vector<Edge>& edges() const { return edges_; }
  /// N_i (eq:ni): for an undirected graph, the nodes sharing an edge with i, ascending.
  const std::vector<int>& neighbors(int i) const { return adj_[static_cast<size_t>(i)]; }
  int degree(int i) const { return static_cast<int>(neighbors(i).size()); }
  int max_degree() const;

  /// Graph Laplacian L = D - A (sparse, n x n).
  Eigen::SparseMatrix<double> laplacian() const;

  /// Connected components, each sorted ascending, ordered by smallest node.
  std::vector<std::vector<int>> components() const;
  bool connected() const { return components().size() == 1; }

  /// Hop distances from a source node (-1 where unreachable); one BFS, O(n + |E|).
  std::vector<int> hop_distances(int source) const;
  /// diam(G): the longest shortest path; throws std::logic_error if G is disconnected.
  int diameter() const;

 private:
  std::vector<std::vector<int>> adj_;
  std::vector<Edge> edges_;
};

/// W of (eqn:defD): W = min_{i0} min_{G_T in T(i0)} max_{E in E_T} sum_i Delta(E; i) d(i).
struct PaperW {
  double value = 0.0;  ///< W, or an upper bound on it when exact == false
  bool exact = false;  ///< true when computed by exhaustive search
  int root = -1;       ///< the root i0 of the best spanning tree found
};

/// Computes W exactly for n <= max_exact_nodes and an upper bound (the best of a
/// shortest-path-tree heuristic over all roots) otherwise. Requires a connected graph.
///
/// Exact method: in a rooted tree the branch sum sum_i Delta(E; i) d(i) of an edge is the sum of
/// the depths of the nodes below it, which is largest for edges at the root; every neighbour of
/// the root can be made a child of the root without increasing any branch sum, and within a
/// branch with a fixed node set the depths are smallest on a BFS tree of that branch. So W is the
/// min over roots of the min over assignments of the remaining nodes to the root's neighbours of
/// the largest branch weight sum_{u in branch} (1 + dist_branch(child, u)).
PaperW paper_W(const Graph& g, int max_exact_nodes = 12);

/// A human-readable description of components, e.g. "{1,2,3} {4,5}", with node labels.
std::string describe_components(const std::vector<std::vector<int>>& comps,
                                const std::vector<int>& labels);

}  // namespace netvmo::obs
