// Graph quantities: Laplacian, connectivity, diameter and W (eqn:defD), the latter against a
// literal brute force over every rooted spanning tree.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <random>

#include "netvmo/observer/graph.hpp"
#include "paper5.hpp"

using namespace netvmo::obs;

namespace {
// The paper's Section 5 graph, 0-based.
Graph paper_graph() {
  return netvmo::test::Paper5().graph;
}

Graph path_graph(int n) {
  std::vector<Graph::Edge> e;
  for (int i = 0; i + 1 < n; ++i) e.emplace_back(i, i + 1);
  return Graph(n, e);
}

// W by definition: every root, every spanning tree (each non-root node picks a parent among its
// neighbours; keep the choices that reach the root), D~ = max over tree edges (parent(v), v) of
// the sum of depths d(i) over the nodes i whose root path uses that edge (the subtree of v).
double brute_force_W(const Graph& g) {
  const int n = g.size();
  double W = std::numeric_limits<double>::infinity();
  for (int root = 0; root < n; ++root) {
    std::vector<int> choice(static_cast<size_t>(n), 0), parent(static_cast<size_t>(n), -1);
    while (true) {
      for (int v = 0; v < n; ++v)
        parent[static_cast<size_t>(v)] =
            v == root ? -1 : g.neighbors(v)[static_cast<size_t>(choice[static_cast<size_t>(v)])];
      std::vector<int> depth(static_cast<size_t>(n), -1);
      bool tree = true;
      for (int v = 0; v < n && tree; ++v) {
        int u = v, d = 0;
        while (u != root && d <= n) {
          u = parent[static_cast<size_t>(u)];
          ++d;
        }
        if (d > n)
          tree = false;
        else
          depth[static_cast<size_t>(v)] = d;
      }
      if (tree) {
        double Dt = 0.0;
        for (int v = 0; v < n; ++v) {
          if (v == root) continue;  // edge (parent(v), v)
          double sum = 0.0;
          for (int i = 0; i < n; ++i) {  // does the path root -> i include edge (parent(v), v)?
            int u = i;
            bool uses = false;
            while (u != root) {
              if (u == v) {
                uses = true;
                break;
              }
              u = parent[static_cast<size_t>(u)];
            }
            if (uses) sum += depth[static_cast<size_t>(i)];
          }
          Dt = std::max(Dt, sum);
        }
        W = std::min(W, Dt);
      }
      int pos = 0;
      while (pos < n) {
        if (pos != root && ++choice[static_cast<size_t>(pos)] < g.degree(pos)) break;
        choice[static_cast<size_t>(pos)] = 0;
        ++pos;
      }
      if (pos == n) break;
    }
  }
  return W;
}

Graph random_connected_graph(int n, double p, std::mt19937& rng) {
  std::bernoulli_distribution coin(p);
  std::vector<Graph::Edge> e;
  for (int i = 1; i < n; ++i) e.emplace_back(std::uniform_int_distribution<int>(0, i - 1)(rng), i);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (coin(rng) && std::find(e.begin(), e.end(), Graph::Edge(i, j)) == e.end() &&
          std::find(e.begin(), e.end(), Graph::Edge(j, i)) == e.end())
        e.emplace_back(i, j);
  return Graph(n, e);
}
}  // namespace

TEST(Graph, LaplacianIsSymmetricWithZeroRowSums) {
  const Eigen::MatrixXd L = Eigen::MatrixXd(paper_graph().laplacian());
  EXPECT_TRUE(L.isApprox(L.transpose()));
  EXPECT_LT((L * Eigen::VectorXd::Ones(5)).norm(), 1e-15);
  EXPECT_EQ(L(0, 0), 3.0);
  EXPECT_EQ(L(0, 1), -1.0);
  EXPECT_EQ(L(0, 3), 0.0);
  // Connected <=> the second smallest eigenvalue is positive.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(L);
  EXPECT_GT(es.eigenvalues()[1], 1e-9);
  // Gershgorin bound used for the step size.
  EXPECT_LE(es.eigenvalues()[4], 2.0 * paper_graph().max_degree());
}

TEST(Graph, RejectsBadEdges) {
  EXPECT_THROW(Graph(3, {{0, 3}}), std::invalid_argument);
  EXPECT_THROW(Graph(3, {{1, 1}}), std::invalid_argument);
  EXPECT_THROW(Graph(3, {{0, 1}, {1, 0}}), std::invalid_argument);
}

TEST(Graph, ComponentsOfDisconnectedGraphAreNamed) {
  const Graph g(5, {{0, 1}, {1, 2}, {3, 4}});
  EXPECT_FALSE(g.connected());
  const auto c = g.components();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(describe_components(c, {1, 2, 3, 4, 5}), "{1,2,3} {4,5}");
  EXPECT_THROW(g.diameter(), std::logic_error);
  EXPECT_THROW(paper_W(g), std::logic_error);
  EXPECT_TRUE(paper_graph().connected());
}

TEST(Graph, Diameter) {
  EXPECT_EQ(paper_graph().diameter(), 2);
  EXPECT_EQ(path_graph(6).diameter(), 5);
  std::vector<Graph::Edge> ring;
  for (int i = 0; i < 8; ++i) ring.emplace_back(i, (i + 1) % 8);
  EXPECT_EQ(Graph(8, ring).diameter(), 4);
}

TEST(Graph, PaperWByHand) {
  // Path 1-2-3-4: root 2, branches {1}: 1 and {3,4}: 1 + 2 = 3.
  EXPECT_EQ(paper_W(path_graph(4)).value, 3.0);
  // Star: every node at depth 1 in its own branch.
  EXPECT_EQ(paper_W(Graph(5, {{0, 1}, {0, 2}, {0, 3}, {0, 4}})).value, 1.0);
  // The paper's graph: any root leaves one node at depth 2 below a depth-1 node.
  const PaperW w = paper_W(paper_graph());
  EXPECT_TRUE(w.exact);
  EXPECT_EQ(w.value, 3.0);
}

TEST(Graph, PaperWExactEqualsBruteForceOnRandomGraphs) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 2 + trial % 6;  // 2..7 nodes
    const Graph g = random_connected_graph(n, 0.3, rng);
    EXPECT_EQ(paper_W(g).value, brute_force_W(g)) << "trial " << trial;
  }
}

TEST(Graph, PaperWHeuristicIsAnUpperBound) {
  std::mt19937 rng(8);
  for (int trial = 0; trial < 20; ++trial) {
    const Graph g = random_connected_graph(9, 0.25, rng);
    const PaperW exact = paper_W(g, 12);
    const PaperW bound = paper_W(g, 0);
    EXPECT_TRUE(exact.exact);
    EXPECT_FALSE(bound.exact);
    EXPECT_GE(bound.value, exact.value);
  }
}
