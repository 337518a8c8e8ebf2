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
//
// Large components (more unknowns than the dense limit) are solved in that
// reduced form: the branch currents are eliminated, leaving the positive
// definite weighted Laplacian
//
//     (G + B Z^-1 B^T) V = -B Z^-1 e,      I = Z^-1 (B^T V + e),
//
// factorised as L D L^T (Cholesky without square roots) after an approximate
// minimum degree (AMD) ordering. The ordering and the elimination tree (the
// symbolic analysis) depend only on which nodes the elements join, so they
// are computed when the topology changes and reused when only an impedance
// does; the numeric factorisation and every solve cost O(nnz(L)), which the
// ordering keeps linear for chains and ladders and near n log n for planar
// meshes. (The supernodal LU with COLAMD on the unreduced, indefinite MNA
// matrix, used before, remains available as SparseMethod::Lu: its ordering
// does not see the symmetry, and its ladder grew as n^1.7.)
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
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

/// What MnaSolver::solve throws when a component's answer is not finite
/// (sources so large that a current or a potential overflowed): the
/// component, so that the caller can name its parts.
class NonFiniteSolution : public std::runtime_error {
 public:
  NonFiniteSolution(std::size_t component, const std::string& message)
      : std::runtime_error(message), component(component) {}
  std::size_t component;  ///< index into the solver's components
};

/// How components above the dense limit are factorised.
enum class SparseMethod {
  /// Branch currents eliminated; L D L^T of the reduced Laplacian with an AMD
  /// ordering, the symbolic analysis reused while the topology stays (default).
  Cholesky,
  /// The unreduced MNA matrix by supernodal LU with COLAMD, analysed afresh at
  /// every factor() (the method before issue 16; kept as the reference the
  /// benchmark and the tests compare against).
  Lu,
};

/// Factorises each connected component of a network once, then solves it for
/// any set of branch sources.
class MnaSolver {
 public:
  /// Components with at most `dense_limit` unknowns use dense LU with partial
  /// pivoting on the MNA matrix; larger ones use `sparse` (see SparseMethod).
  explicit MnaSolver(std::size_t dense_limit = 64, SparseMethod sparse = SparseMethod::Cholesky);
  ~MnaSolver();
  MnaSolver(MnaSolver&&) noexcept;
  MnaSolver& operator=(MnaSolver&&) noexcept;

  /// Partitions the network into connected components, chooses each one's
  /// ground (node a of its first branch, else its lowest node) and factorises
  /// every component that contains a branch (one without cannot carry
  /// current). Throws std::invalid_argument on a non-positive or non-finite
  /// conductance or impedance, or an out-of-range node.
  /// When the network joins the same nodes by the same elements (in the same
  /// order) as at the last call, only the values changed: the components, the
  /// ground and the sparse orderings are kept and only the numeric
  /// factorisation is redone.
  void factor(const Network& network);

  /// Solves for the branch sources `e` (one per branch, V). Writes the node
  /// potentials relative to their component's ground (V) and the branch
  /// currents (A). Components whose sources are all zero are not solved: their
  /// answer is zero. Conductance currents follow as g (V_a - V_b).
  /// Throws NonFiniteSolution if a solution is not finite (sources whose
  /// currents overflow double; the check keeps a NaN or an infinity from
  /// spreading).
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
  /// Symbolic analyses (ordering, elimination tree) of sparse components since
  /// construction: with SparseMethod::Cholesky they move only when the
  /// topology changes.
  std::uint64_t symbolic_analyses() const { return symbolic_analyses_; }
  std::size_t dense_limit() const { return dense_limit_; }
  SparseMethod sparse_method() const { return sparse_method_; }

 private:
  struct Component;
  /// The (a, b) pairs of the last network, conductances then branches: equal
  /// pairs mean the same topology.
  bool same_topology(const Network& network) const;
  void partition(const Network& network);
  void factor_components(const Network& network);
  /// Nodes (a, b) of branch k of the factored network.
  std::pair<std::uint32_t, std::uint32_t> branch_ends(std::size_t k) const {
    return topology_[1 + topology_[0].second + k];
  }

  std::size_t dense_limit_;
  SparseMethod sparse_method_;
  std::uint32_t node_count_ = 0;
  std::size_t branch_count_ = 0;
  std::vector<std::uint32_t> component_of_node_;
  std::vector<Component> components_;
  std::vector<std::int32_t> node_row_;    // row of each node in its component, -1: ground
  std::vector<std::int32_t> branch_row_;  // row of each branch's current in its component
  // Reduced (L D L^T) components: each node's position in the factor's
  // permuted order, -1 for the ground (solve() works in that order).
  std::vector<std::int32_t> node_pos_;
  std::vector<std::uint32_t> conductances_of_;     // conductance indices grouped by component
  std::vector<std::uint32_t> conductances_start_;  // component c: [start[c], start[c + 1])
  std::vector<std::pair<std::uint32_t, std::uint32_t>> topology_;
  std::vector<double>
      branch_z_;  // impedance of each branch, Ohm (the reduced form's solve needs it)
  std::uint64_t factorizations_ = 0;
  std::uint64_t symbolic_analyses_ = 0;
};

/// For each edge (a, b) of an undirected multigraph on `node_count` nodes,
/// whether it lies on a cycle, i.e. is not a bridge: removing it leaves its
/// ends connected. A self-loop lies on a cycle; so do two parallel edges.
/// Iterative Tarjan lowlink, O(nodes + edges).
std::vector<bool> edges_on_cycles(std::uint32_t node_count,
                                  std::span<const std::pair<std::uint32_t, std::uint32_t>> edges);

}  // namespace alloy::electricity
