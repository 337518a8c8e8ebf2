// Tests for resolvers/electricity/mna.hpp: the MNA solver against Ohm's and
// Kirchhoff's laws worked by hand, dense against sparse LU, components that
// cannot carry current, and the bridge finder behind circuit_closed.
#include "resolvers/electricity/mna.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace alloy::electricity {
namespace {

struct Solution {
  std::vector<double> v, i;
};

Solution solve(const MnaSolver& s, const Network& n, std::vector<double> e) {
  Solution out{std::vector<double>(n.node_count), std::vector<double>(n.branches.size())};
  s.solve(e, out.v, out.i);
  return out;
}

TEST(MnaSolver, SeriesDividerObeysOhmsLaw) {
  // Battery (10 V, 0.5 Ohm) from node 0 (-) to node 1 (+), then 100 Ohm to
  // node 2 and 300 Ohm back to node 0.
  Network n{.node_count = 3,
            .conductances = {{1, 2, 1.0 / 100}, {2, 0, 1.0 / 300}},
            .branches = {{0, 1, 0.5}}};
  MnaSolver s;
  s.factor(n);
  const Solution x = solve(s, n, {10.0});
  const double i = 10.0 / (0.5 + 100 + 300);
  EXPECT_NEAR(x.i[0], i, 1e-15);
  EXPECT_EQ(x.v[0], 0.0);  // the ground: the battery's negative terminal
  EXPECT_NEAR(x.v[1], 10.0 - 0.5 * i, 1e-12);
  EXPECT_NEAR(x.v[2], 300 * i, 1e-12);
  EXPECT_EQ(s.component_count(), 1u);
  EXPECT_EQ(s.ground(0), 0u);
  EXPECT_EQ(s.factorizations(), 1u);
}

TEST(MnaSolver, KirchhoffsLawsHoldInABridgeWithTwoSources) {
  // A Wheatstone-like bridge with two batteries: check KCL at every node and
  // each battery's branch equation, rather than a hand-solved value.
  Network n{.node_count = 5,
            .conductances = {{1, 2, 1 / 10.0},
                             {1, 3, 1 / 20.0},
                             {2, 3, 1 / 30.0},
                             {2, 0, 1 / 40.0},
                             {3, 0, 1 / 50.0},
                             {4, 2, 1 / 5.0}},
            .branches = {{0, 1, 0.2}, {0, 4, 1.0}}};
  MnaSolver s;
  s.factor(n);
  const std::vector<double> e = {12.0, 3.0};
  const Solution x = solve(s, n, e);
  std::vector<double> net_out(n.node_count, 0.0);  // current leaving each node
  for (const auto& g : n.conductances) {
    const double i = g.g * (x.v[g.a] - x.v[g.b]);
    net_out[g.a] += i, net_out[g.b] -= i;
  }
  for (std::size_t k = 0; k < n.branches.size(); ++k) {
    net_out[n.branches[k].a] += x.i[k], net_out[n.branches[k].b] -= x.i[k];
    EXPECT_NEAR(x.v[n.branches[k].b] - x.v[n.branches[k].a], e[k] - n.branches[k].z * x.i[k],
                1e-12);
  }
  for (double r : net_out) EXPECT_NEAR(r, 0.0, 1e-13);
}

TEST(MnaSolver, OpenCircuitCarriesNoCurrentAndShowsTheEmf) {
  Network n{.node_count = 3, .conductances = {{1, 2, 1.0}}, .branches = {{0, 1, 0.1}}};
  MnaSolver s;
  s.factor(n);
  const Solution x = solve(s, n, {1.5});
  EXPECT_EQ(x.i[0], 0.0);
  EXPECT_DOUBLE_EQ(x.v[1], 1.5);
  EXPECT_DOUBLE_EQ(x.v[2], 1.5);  // a dead end sits at the potential it hangs from
}

TEST(MnaSolver, ComponentsAreGroundedAndSolvedSeparately) {
  // Two circuits and a lone node; only the components with a branch are factorised.
  Network n{.node_count = 6,
            .conductances = {{1, 0, 1.0}, {3, 4, 0.5}},
            .branches = {{0, 1, 1.0}, {4, 3, 1.0}}};
  MnaSolver s;
  s.factor(n);
  ASSERT_EQ(s.component_count(), 4u);  // {0,1}, {2}, {3,4}, {5}
  EXPECT_EQ(s.factorizations(), 2u);
  EXPECT_EQ(s.ground(2), 4u);  // node a of the component's first branch
  const Solution x = solve(s, n, {2.0, 4.0});
  EXPECT_DOUBLE_EQ(x.i[0], 1.0);        // 2 V over 1 + 1 Ohm
  EXPECT_DOUBLE_EQ(x.i[1], 4.0 / 3.0);  // 4 V over 1 + 2 Ohm
  EXPECT_EQ(x.v[2], 0.0);
  EXPECT_EQ(x.v[5], 0.0);
  // A component whose sources are all zero is not solved, and answers zero.
  const Solution y = solve(s, n, {0.0, 4.0});
  EXPECT_EQ(y.i[0], 0.0);
  EXPECT_EQ(y.v[1], 0.0);
}

TEST(MnaSolver, DenseAndSparseLuAgree) {
  // A resistor ladder of 150 rungs fed by two batteries: 300 nodes, well past
  // the dense limit of the second solver.
  Network n;
  const std::uint32_t rungs = 150;
  n.node_count = 2 * rungs;
  for (std::uint32_t k = 0; k + 1 < rungs; ++k) {
    n.conductances.push_back({2 * k, 2 * k + 2, 1.0 / (1.0 + 0.01 * k)});
    n.conductances.push_back({2 * k + 1, 2 * k + 3, 1.0 / (2.0 + 0.02 * k)});
  }
  for (std::uint32_t k = 0; k < rungs; ++k)
    n.conductances.push_back({2 * k, 2 * k + 1, 1.0 / (50.0 + k)});
  n.branches = {{0, 1, 0.1}, {2 * rungs - 1, 2 * rungs - 2, 0.3}};
  MnaSolver dense(1000), sparse(8);
  dense.factor(n);
  sparse.factor(n);
  ASSERT_TRUE(dense.dense(0));
  ASSERT_FALSE(sparse.dense(0));
  const Solution a = solve(dense, n, {9.0, 4.5}), b = solve(sparse, n, {9.0, 4.5});
  for (std::size_t i = 0; i < a.v.size(); ++i) EXPECT_NEAR(a.v[i], b.v[i], 1e-11);
  for (std::size_t k = 0; k < a.i.size(); ++k) EXPECT_NEAR(a.i[k], b.i[k], 1e-11);
  EXPECT_GT(std::abs(a.i[0]), 0.01);  // a real answer, not two zeros
}

/// A random network: a few components, parallel elements, self-loops, nodes
/// reached only through a branch, a component with no branch, impedances over
/// six decades.
Network random_network(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> node(0, 199);
  std::uniform_real_distribution<double> decade(-3, 3);
  Network n;
  n.node_count = 220;  // nodes 200..219 stay isolated
  for (int i = 0; i < 500; ++i) {
    const std::uint32_t a = node(rng), b = i % 50 == 0 ? a : (a + 1 + node(rng) % 9) % 200;
    n.conductances.push_back({a, b, std::pow(10.0, decade(rng))});
  }
  for (int k = 0; k < 40; ++k) {
    const std::uint32_t a = node(rng), b = k == 7 ? a : node(rng);
    n.branches.push_back({a, b, std::pow(10.0, decade(rng))});
  }
  n.branches.push_back({n.branches[3].a, n.branches[3].b, 0.5});  // parallel to branch 3
  n.branches.push_back({200, 201, 2.0});                          // a battery alone: open circuit
  n.branches.push_back({202, 203, 1.0});  // a source in series with a resistor, looped
  n.conductances.push_back({202, 203, 4.0});
  return n;
}

TEST(MnaSolver, ReducedLdltAgreesWithDenseAndSparseLuOnRandomNetworks) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Network n = random_network(seed);
    MnaSolver dense(100000), lu(0, SparseMethod::Lu), ldlt(0, SparseMethod::Cholesky);
    dense.factor(n), lu.factor(n), ldlt.factor(n);
    ASSERT_FALSE(ldlt.dense(0));
    std::vector<double> e(n.branches.size());
    for (std::size_t k = 0; k < e.size(); ++k) e[k] = std::sin(double(k + seed)) * 10;
    const Solution a = solve(dense, n, e), b = solve(lu, n, e), c = solve(ldlt, n, e);
    double scale_v = 0, scale_i = 0;
    for (double v : a.v) scale_v = std::max(scale_v, std::abs(v));
    for (double i : a.i) scale_i = std::max(scale_i, std::abs(i));
    ASSERT_GT(scale_i, 0.1);
    for (std::size_t v = 0; v < a.v.size(); ++v) {
      EXPECT_NEAR(c.v[v], a.v[v], 1e-9 * scale_v) << "seed " << seed << " node " << v;
      EXPECT_NEAR(b.v[v], a.v[v], 1e-9 * scale_v) << "seed " << seed << " node " << v;
    }
    for (std::size_t k = 0; k < a.i.size(); ++k)
      EXPECT_NEAR(c.i[k], a.i[k], 1e-9 * scale_i) << "seed " << seed << " branch " << k;
    // The open battery: no current, its emf across it; the looped one: e / (z + R).
    const std::size_t open = n.branches.size() - 2, looped = n.branches.size() - 1;
    EXPECT_EQ(c.i[open], 0.0);
    EXPECT_NEAR(c.v[201] - c.v[200], e[open], 1e-12);
    EXPECT_NEAR(c.i[looped], e[looped] / (1.0 + 0.25), 1e-12);
  }
}

TEST(MnaSolver, SymbolicAnalysisIsKeptWhileTheTopologyStays) {
  Network n = random_network(11);
  MnaSolver s(0);
  s.factor(n);
  const std::uint64_t analysed = s.symbolic_analyses(), factored = s.factorizations();
  ASSERT_GT(analysed, 0u);
  // New values on the same topology: numeric factorisation only, and the
  // answer of a solver that starts afresh.
  for (auto& g : n.conductances) g.g *= 1.5;
  for (auto& b : n.branches) b.z *= 0.7;
  s.factor(n);
  EXPECT_EQ(s.symbolic_analyses(), analysed);
  EXPECT_GT(s.factorizations(), factored);
  MnaSolver fresh(0);
  fresh.factor(n);
  const std::vector<double> e(n.branches.size(), 3.0);
  const Solution a = solve(s, n, e), b = solve(fresh, n, e);
  for (std::size_t v = 0; v < a.v.size(); ++v) EXPECT_NEAR(a.v[v], b.v[v], 1e-12);
  for (std::size_t k = 0; k < a.i.size(); ++k) EXPECT_NEAR(a.i[k], b.i[k], 1e-12);
  // A changed topology (an element moved to other nodes) is analysed again.
  n.conductances[5].b = (n.conductances[5].b + 3) % 200;
  s.factor(n);
  EXPECT_GT(s.symbolic_analyses(), analysed);
  fresh.factor(n);
  const Solution c = solve(s, n, e), d = solve(fresh, n, e);
  for (std::size_t v = 0; v < c.v.size(); ++v) EXPECT_NEAR(c.v[v], d.v[v], 1e-12);
}

TEST(MnaSolver, ParallelElementsAndSelfLoopsAreStampedCorrectly) {
  // Two 10 Ohm resistors in parallel, and a branch shorted onto one node.
  Network n{.node_count = 2,
            .conductances = {{1, 0, 0.1}, {0, 1, 0.1}, {1, 1, 5.0}},
            .branches = {{0, 1, 1.0}, {1, 1, 2.0}}};
  MnaSolver s;
  s.factor(n);
  const Solution x = solve(s, n, {6.0, 3.0});
  EXPECT_NEAR(x.i[0], 6.0 / (1.0 + 5.0), 1e-12);
  EXPECT_NEAR(x.i[1], 3.0 / 2.0, 1e-12);  // a branch from a node to itself: I = e / z
}

TEST(MnaSolver, RejectsNonPositiveOrNonFiniteValues) {
  MnaSolver s;
  EXPECT_THROW(s.factor({.node_count = 2, .conductances = {{0, 1, 0.0}}}), std::invalid_argument);
  EXPECT_THROW(s.factor({.node_count = 2, .branches = {{0, 1, -1.0}}}), std::invalid_argument);
  EXPECT_THROW(s.factor({.node_count = 2, .branches = {{0, 1, NAN}}}), std::invalid_argument);
  EXPECT_THROW(s.factor({.node_count = 2, .conductances = {{0, 2, 1.0}}}), std::invalid_argument);
}

TEST(EdgesOnCycles, FindsBridgesInAMultigraph) {
  using E = std::pair<std::uint32_t, std::uint32_t>;
  // Triangle 0-1-2, bridge 2-3, parallel pair 3-4 (a cycle), pendant 4-5,
  // self-loop at 6, isolated 7.
  const std::vector<E> edges = {{0, 1}, {1, 2}, {2, 0}, {2, 3}, {3, 4}, {4, 3}, {4, 5}, {6, 6}};
  const std::vector<bool> on = edges_on_cycles(8, edges);
  EXPECT_EQ(on, (std::vector<bool>{true, true, true, false, true, true, false, true}));
  EXPECT_EQ(edges_on_cycles(3, std::vector<E>{{0, 1}, {1, 2}}), (std::vector<bool>{false, false}));
}

}  // namespace
}  // namespace alloy::electricity
