// Modified nodal analysis (MNA) of a linear resistive network with Thevenin
// branches: the numerical core of the electricity resolver, free of the world
// so that it can be tested and reasoned about on its own.
//
// Unknowns: the potential of every node but one per connected component (its
// ground), and the current of every Thevenin branch. Conductances (wires,
// contacts, resistors) are stamped into the nodal block; a Thevenin branch
// (battery: emf e in series with r; coil: backward-Euler companion, see
// docs/electricity.md) adds one row and one column:
//
//     KCL at node n:   sum_conductances g (V_n - V_m) + sum_branches (+I if n = a, -I if n = b) = 0
//     branch k:        V_a - V_b - z_k I_k = -e_k         (so V_b - V_a = e_k - z_k I_k)
//
// The matrix depends only on the topology and the impedances; the right-hand
// side only on the branch sources e_k. factor() is therefore called when the
// topology or an impedance changes, solve() every step.
//
// Every conductance and every branch impedance must be positive and finite.
// Then each grounded component is regular: eliminating the branch currents
// (I = (V_a - V_b + e) / z) leaves a weighted graph Laplacian of a connected
// graph with one node removed, which is positive definite. The MNA matrix
// itself is symmetric but indefinite (the branch block is -z), hence LU with
// partial pivoting rather than Cholesky.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace alloy::electricity {

/// A conductance between two nodes (wire, contact, resistor), S.
struct Conductance {
  std::uint32_t a = 0, b = 0;
  double g = 0;  ///< S, > 0
  friend bool operator==(const Conductance&, const Conductance&) = default;
};

/// A Thevenin branch: source e (V) in series with impedance z (Ohm) from node a
/// to node b. Its current I (A) flows from a to b through the branch, and
/// V_b - V_a = e - z I.
struct TheveninBranch {
  std::uint32_t a = 0, b = 0;
  double z = 0;  ///< Ohm, > 0
  friend bool operator==(const TheveninBranch&, const TheveninBranch&) = default;
};

/// The network as the solver sees it. Nodes are dense indices [0, node_count).
struct Network {
  std::uint32_t node_count = 0;
  std::vector<Conductance> conductances;
  std::vector<TheveninBranch> branches;
  friend bool operator==(const Network&, const Network&) = default;
};

/// Factorises each connected component of a network once, then solves it for
/// any set of branch sources.
class MnaSolver {
 public:
  /// Components with at most `dense_limit` unknowns use dense LU with partial
  /// pivoting; larger ones use sparse supernodal LU with a COLAMD ordering.
  explicit MnaSolver(std::size_t dense_limit = 64);
  ~MnaSolver();
  MnaSolver(MnaSolver&&) noexcept;
  MnaSolver& operator=(MnaSolver&&) noexcept;

  /// Partitions the network into connected components, chooses each one's
  /// ground (node a of its first branch, else its lowest node) and factorises
  /// every component that contains a branch (one without cannot carry
  /// current). Throws std::invalid_argument on a non-positive or non-finite
  /// conductance or impedance, or an out-of-range node.
  void factor(const Network& network);

  /// Solves for the branch sources `e` (one per branch, V). Writes the node
  /// potentials relative to their component's ground (V) and the branch
  /// currents (A). Components whose sources are all zero are not solved: their
  /// answer is zero. Conductance currents follow as g (V_a - V_b).
  /// Throws std::runtime_error if a solution is not finite (it cannot be for a
  /// network that factor() accepted; the check keeps a NaN from spreading).
  void solve(std::span<const double> e, std::span<double> potential,
             std::span<double> current) const;

  /// Connected component of each node, numbered in order of first node.
  std::span<const std::uint32_t> component_of_node() const { return component_of_node_; }
  std::size_t component_count() const;
  /// The ground node of a component.
  std::uint32_t ground(std::size_t component) const;
  /// Unknowns of a component: its nodes but the ground, plus its branches.
  std::size_t unknowns(std::size_t component) const;
  /// Whether a component was factorised with the dense (true) or sparse LU.
  bool dense(std::size_t component) const;

  /// Component factorisations since construction (the cost that topology
  /// changes incur; tests assert it moves only when it should).
  std::uint64_t factorizations() const { return factorizations_; }
  std::size_t dense_limit() const { return dense_limit_; }

 private:
  struct Component;
  std::size_t dense_limit_;
  std::uint32_t node_count_ = 0;
  std::size_t branch_count_ = 0;
  std::vector<std::uint32_t> component_of_node_;
  std::vector<Component> components_;
  std::vector<std::int32_t> node_row_;    // row of each node in its component, -1: ground
  std::vector<std::int32_t> branch_row_;  // row of each branch's current in its component
  std::uint64_t factorizations_ = 0;
};

/// For each edge (a, b) of an undirected multigraph on `node_count` nodes,
/// whether it lies on a cycle, i.e. is not a bridge: removing it leaves its
/// ends connected. A self-loop lies on a cycle; so do two parallel edges.
/// Iterative Tarjan lowlink, O(nodes + edges).
std::vector<bool> edges_on_cycles(std::uint32_t node_count,
                                  std::span<const std::pair<std::uint32_t, std::uint32_t>> edges);

}  // namespace alloy::electricity
