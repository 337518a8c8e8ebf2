// Tests for resolvers/electricity/mna.hpp: the MNA solver against Ohm's and
// Kirchhoff's laws worked by hand, dense against sparse LU, components that
// cannot carry current, and the bridge finder behind circuit_closed.
#include "resolvers/electricity/mna.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
