#include "resolvers/electricity/mna.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace alloy::electricity {

namespace {

/// Union-find with path halving; components are found once per factor().
struct DisjointSets {
  explicit DisjointSets(std::uint32_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), 0u);
  }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // deterministic root: the lower index
  }
  std::vector<std::uint32_t> parent;
};

constexpr std::int32_t kGround = -1;

}  // namespace

using SparseMatrix = Eigen::SparseMatrix<double>;
using SupernodalLu = Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>>;
using ReducedLdlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;

struct MnaSolver::Component {
  std::vector<std::uint32_t> nodes;     // ascending
  std::vector<std::uint32_t> branches;  // indices into Network::branches, in network order
  std::uint32_t ground = 0;
  std::size_t unknowns = 0;
  bool dense = true;
  bool factored = false;
  Eigen::PartialPivLU<Eigen::MatrixXd> dense_lu;
  // Neither sparse factorisation is copyable nor movable; keep them behind pointers.
  std::unique_ptr<SupernodalLu> sparse_lu;
  // Kept across factor() calls while the topology stays: it holds the AMD
  // ordering and the elimination tree, so a new impedance costs only the
  // numeric factorisation.
  std::unique_ptr<ReducedLdlt> ldlt;
  // Work buffers, sized once. The reduced form uses x alone: the right-hand
  // side, then the solution, both in the factor's permuted order.
  mutable Eigen::VectorXd rhs, x;
};

namespace {
/// Solves A y = b in place, where y holds b in the factor's (permuted) order
/// on entry and the solution in that order on return, from A's factors
/// P^T L D L^T P. The caller scatters the right-hand side straight into the
/// permuted positions and gathers the solution from them (node_pos_), so the
/// per-step path has no permutation pass and no temporary: at 20,000 nodes
/// those passes and Eigen's copies cost about as much as the sweeps. The
/// floating-point operations are Eigen's, in Eigen's order (so the same
/// bits): L y = y (unit lower, by columns), y = D^-1 y, L^T y = y (by
/// columns of L, as rows of L^T).
void solve_ldlt_permuted(const ReducedLdlt& f, Eigen::VectorXd& y) {
  const auto& l = f.matrixL().nestedExpression();
  const Eigen::Index m = y.size();
  if (!l.isCompressed()) {  // not seen with Eigen 3.4; the library's own solve then
    const auto& perm = f.permutationP().indices();
    Eigen::VectorXd b(m);
    for (Eigen::Index i = 0; i < m; ++i) b[i] = y[perm.size() > 0 ? perm[i] : i];
    const Eigen::VectorXd x = f.solve(b);
    for (Eigen::Index i = 0; i < m; ++i) y[perm.size() > 0 ? perm[i] : i] = x[i];
    return;
  }
  const Eigen::VectorXd& d = f.vectorD();
  const int* outer = l.outerIndexPtr();
  const int* inner = l.innerIndexPtr();
  const double* value = l.valuePtr();
  // Eigen's L holds the strictly lower part only (D apart): no diagonal to skip.
  for (Eigen::Index j = 0; j < m; ++j) {
    const double yj = y[j];
    for (int p = outer[j]; p < outer[j + 1]; ++p) y[inner[p]] -= yj * value[p];
  }
  // D^-1 and L^T fused into one backward pass: y[j] is scaled just before
  // its row of L^T is applied (the rows below are final by then).
  for (Eigen::Index j = m - 1; j >= 0; --j) {
    double s = (1.0 / d[j]) * y[j];
    for (int p = outer[j]; p < outer[j + 1]; ++p) s -= value[p] * y[inner[p]];
    y[j] = s;
  }
}
}  // namespace

MnaSolver::MnaSolver(std::size_t dense_limit, SparseMethod sparse)
    : dense_limit_(dense_limit), sparse_method_(sparse) {}
MnaSolver::~MnaSolver() = default;
MnaSolver::MnaSolver(MnaSolver&&) noexcept = default;
MnaSolver& MnaSolver::operator=(MnaSolver&&) noexcept = default;

std::size_t MnaSolver::component_count() const {
  return components_.size();
}
std::uint32_t MnaSolver::ground(std::size_t c) const {
  return components_.at(c).ground;
}
std::size_t MnaSolver::unknowns(std::size_t c) const {
  return components_.at(c).unknowns;
}
bool MnaSolver::dense(std::size_t c) const {
  return components_.at(c).dense;
}

bool MnaSolver::same_topology(const Network& net) const {
  if (topology_.size() != 1 + net.conductances.size() + net.branches.size() ||
      topology_[0] != std::pair{net.node_count, std::uint32_t(net.conductances.size())})
    return false;
  std::size_t i = 1;
  for (const Conductance& c : net.conductances)
    if (topology_[i++] != std::pair{c.a, c.b}) return false;
  for (const TheveninBranch& b : net.branches)
    if (topology_[i++] != std::pair{b.a, b.b}) return false;
  return true;
}

void MnaSolver::partition(const Network& net) {
  const std::uint32_t n = net.node_count;
  // Connected components over every element: conductances and branches alike.
  DisjointSets sets(n);
  for (const auto& c : net.conductances) sets.unite(c.a, c.b);
  for (const auto& br : net.branches) sets.unite(br.a, br.b);
  node_count_ = n;
  branch_count_ = net.branches.size();
  component_of_node_.assign(n, 0);
  components_.clear();
  std::vector<std::int64_t> component_of_root(n, -1);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t r = sets.find(v);
    if (component_of_root[r] < 0) {
      component_of_root[r] = std::int64_t(components_.size());
      components_.emplace_back();
    }
    component_of_node_[v] = std::uint32_t(component_of_root[r]);
    components_[component_of_node_[v]].nodes.push_back(v);
  }
  for (std::uint32_t k = 0; k < net.branches.size(); ++k)
    components_[component_of_node_[net.branches[k].a]].branches.push_back(k);

  // Conductances grouped by component (a counting sort: stable, linear).
  conductances_start_.assign(components_.size() + 1, 0);
  for (const Conductance& g : net.conductances) ++conductances_start_[component_of_node_[g.a] + 1];
  for (std::size_t c = 0; c < components_.size(); ++c)
    conductances_start_[c + 1] += conductances_start_[c];
  conductances_of_.resize(net.conductances.size());
  {
    std::vector<std::uint32_t> fill(conductances_start_.begin(), conductances_start_.end() - 1);
    for (std::uint32_t i = 0; i < net.conductances.size(); ++i)
      conductances_of_[fill[component_of_node_[net.conductances[i].a]]++] = i;
  }

  // Local numbering: node v of a component -> row, ground -> kGround; branch
  // k -> row after the component's nodes. One array per network, filled per
  // component (components are disjoint, so entries never clash).
  node_row_.assign(n, kGround);
  node_pos_.assign(n, kGround);
  branch_row_.assign(net.branches.size(), kGround);
  for (Component& comp : components_) {
    // The ground: node a of the first branch. The resolver lists batteries
    // first, terminal 0 (negative) as a, so potentials read as the voltmeter
    // of a kit user whose black lead is on the first battery's minus.
    comp.ground =
        comp.branches.empty() ? comp.nodes.front() : net.branches[comp.branches.front()].a;
    std::int32_t row = 0;
    for (std::uint32_t v : comp.nodes)
      if (v != comp.ground) node_row_[v] = row++;
    for (std::uint32_t k : comp.branches) branch_row_[k] = row++;
    comp.unknowns = std::size_t(row);
    comp.dense = comp.unknowns <= dense_limit_;
  }

  topology_.clear();
  topology_.reserve(1 + net.conductances.size() + net.branches.size());
  topology_.emplace_back(n, std::uint32_t(net.conductances.size()));
  for (const Conductance& c : net.conductances) topology_.emplace_back(c.a, c.b);
  for (const TheveninBranch& b : net.branches) topology_.emplace_back(b.a, b.b);
}

void MnaSolver::factor(const Network& net) {
  const std::uint32_t n = net.node_count;
  auto check = [&](std::uint32_t a, std::uint32_t b, double v, const char* what, std::size_t i) {
    if (a >= n || b >= n)
      throw std::invalid_argument(std::string(what) + " " + std::to_string(i) +
                                  " joins a node that does not exist");
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string(what) + " " + std::to_string(i) +
                                  " must be positive and finite, got " + std::to_string(v));
  };
  for (std::size_t i = 0; i < net.conductances.size(); ++i)
    check(net.conductances[i].a, net.conductances[i].b, net.conductances[i].g, "conductance", i);
  for (std::size_t i = 0; i < net.branches.size(); ++i)
    check(net.branches[i].a, net.branches[i].b, net.branches[i].z, "branch impedance", i);

  if (!same_topology(net)) partition(net);
  branch_z_.resize(net.branches.size());
  for (std::size_t k = 0; k < net.branches.size(); ++k) branch_z_[k] = net.branches[k].z;

  try {
    factor_components(net);
  } catch (...) {
    // A failed factor() leaves nothing to reuse (the next one starts afresh)
    // and nothing to solve (solve() then refuses every size).
    topology_.clear();
    components_.clear();
    node_count_ = 0, branch_count_ = 0;
    throw;
  }
}

void MnaSolver::factor_components(const Network& net) {
  std::vector<Eigen::Triplet<double>> t;
  for (std::size_t ci = 0; ci < components_.size(); ++ci) {
    Component& comp = components_[ci];
    comp.factored = false;
    if (comp.branches.empty()) continue;  // no source, no current: nothing to factorise
    const std::span<const std::uint32_t> conductances(
        conductances_of_.data() + conductances_start_[ci],
        conductances_start_[ci + 1] - conductances_start_[ci]);
    t.clear();
    auto add = [&](std::int32_t r, std::int32_t c, double v) {
      if (r != kGround && c != kGround) t.emplace_back(r, c, v);
    };
    auto stamp = [&](std::uint32_t a, std::uint32_t b, double g) {
      const std::int32_t ra = node_row_[a], rb = node_row_[b];
      add(ra, ra, g), add(rb, rb, g), add(ra, rb, -g), add(rb, ra, -g);
    };
    const bool reduced = !comp.dense && sparse_method_ == SparseMethod::Cholesky;
    if (reduced) {
      // The Laplacian of the component with every branch a conductance 1/z;
      // the ground's row and column are left out.
      t.reserve(4 * (conductances.size() + comp.branches.size()));
      for (std::uint32_t i : conductances)
        if (net.conductances[i].a != net.conductances[i].b)
          stamp(net.conductances[i].a, net.conductances[i].b, net.conductances[i].g);
      for (std::uint32_t k : comp.branches)
        if (net.branches[k].a != net.branches[k].b)
          stamp(net.branches[k].a, net.branches[k].b, 1.0 / net.branches[k].z);
      const Eigen::Index m = Eigen::Index(comp.nodes.size() - 1);
      comp.rhs.resize(0);  // the reduced solve works in x alone, in the factor's order
      comp.x.setZero(m);
      if (m > 0) {
        SparseMatrix a(m, m);
        a.setFromTriplets(t.begin(), t.end());  // sums duplicates (parallel elements)
        if (!comp.ldlt) {
          comp.ldlt = std::make_unique<ReducedLdlt>();
          comp.ldlt->analyzePattern(a);
          ++symbolic_analyses_;
        }
        comp.ldlt->factorize(a);
        if (comp.ldlt->info() != Eigen::Success)
          throw std::runtime_error("electric network component " + std::to_string(ci) +
                                   " is singular");
        // Each node's place in the factor's order: solve() scatters into it
        // and gathers from it. The ordering is the symbolic analysis's, so
        // this changes only with the topology; it is O(nodes) either way.
        const auto& perm = comp.ldlt->permutationP().indices();
        for (std::uint32_t v : comp.nodes)
          if (const std::int32_t r = node_row_[v]; r != kGround)
            node_pos_[v] = perm.size() > 0 ? perm[r] : r;
      }
    } else {
      t.reserve(4 * conductances.size() + 5 * comp.branches.size());
      for (std::uint32_t i : conductances)
        if (net.conductances[i].a != net.conductances[i].b)  // a self-loop carries nothing
          stamp(net.conductances[i].a, net.conductances[i].b, net.conductances[i].g);
      for (std::uint32_t k : comp.branches) {
        const TheveninBranch& br = net.branches[k];
        const std::int32_t ra = node_row_[br.a], rb = node_row_[br.b], rk = branch_row_[k];
        add(ra, rk, 1.0), add(rb, rk, -1.0);  // I leaves a, enters b
        add(rk, ra, 1.0), add(rk, rb, -1.0), add(rk, rk, -br.z);
      }
      SparseMatrix a(Eigen::Index(comp.unknowns), Eigen::Index(comp.unknowns));
      a.setFromTriplets(t.begin(), t.end());  // sums duplicates (parallel elements)
      if (comp.dense) {
        comp.dense_lu.compute(Eigen::MatrixXd(a));
      } else {
        a.makeCompressed();
        comp.sparse_lu = std::make_unique<SupernodalLu>();
        comp.sparse_lu->analyzePattern(a);
        ++symbolic_analyses_;
        comp.sparse_lu->factorize(a);
        if (comp.sparse_lu->info() != Eigen::Success)
          throw std::runtime_error("electric network component " + std::to_string(ci) +
                                   " is singular: " + comp.sparse_lu->lastErrorMessage());
      }
      comp.rhs.setZero(Eigen::Index(comp.unknowns));
      comp.x.setZero(Eigen::Index(comp.unknowns));
    }
    comp.factored = true;
    ++factorizations_;
  }
}

void MnaSolver::solve(std::span<const double> e, std::span<double> potential,
                      std::span<double> current) const {
  if (e.size() != branch_count_ || potential.size() != node_count_ ||
      current.size() != branch_count_)
    throw std::invalid_argument("MnaSolver::solve: sizes do not match the factored network");
  for (std::size_t ci = 0; ci < components_.size(); ++ci) {
    const Component& comp = components_[ci];
    bool driven = false;
    for (std::uint32_t k : comp.branches)
      if (e[k] != 0.0) {
        driven = true;
        break;
      }
    if (!driven) {  // no source anywhere in the component: everything rests at zero
      for (std::uint32_t v : comp.nodes) potential[v] = 0;
      for (std::uint32_t k : comp.branches) current[k] = 0;
      continue;
    }
    if (!comp.dense && sparse_method_ == SparseMethod::Cholesky) {
      // Reduced form: each branch's source as the current e/z it would drive
      // through a short, injected at its ends; then I = (V_a - V_b + e) / z.
      // The right-hand side goes straight to the factor's order (node_pos_).
      Eigen::VectorXd& y = comp.x;
      y.setZero();
      for (std::uint32_t k : comp.branches) {
        const auto [a, b] = branch_ends(k);
        const double w = e[k] / branch_z_[k];
        if (a != comp.ground) y[node_pos_[a]] -= w;
        if (b != comp.ground) y[node_pos_[b]] += w;
      }
      if (comp.ldlt) solve_ldlt_permuted(*comp.ldlt, y);
      if (!y.allFinite())
        throw NonFiniteSolution(
            ci, "electric network component " + std::to_string(ci) + " gave a non-finite solution");
      for (std::uint32_t v : comp.nodes) potential[v] = v == comp.ground ? 0.0 : y[node_pos_[v]];
      for (std::uint32_t k : comp.branches) {
        const auto [a, b] = branch_ends(k);
        current[k] = (potential[a] - potential[b] + e[k]) / branch_z_[k];
      }
      continue;
    }
    for (std::uint32_t k : comp.branches) comp.rhs[branch_row_[k]] = -e[k];
    if (comp.dense)
      comp.x = comp.dense_lu.solve(comp.rhs);
    else
      comp.x = comp.sparse_lu->solve(comp.rhs);
    if (!comp.x.allFinite())
      throw NonFiniteSolution(
          ci, "electric network component " + std::to_string(ci) + " gave a non-finite solution");
    for (std::uint32_t v : comp.nodes) potential[v] = v == comp.ground ? 0.0 : comp.x[node_row_[v]];
    for (std::uint32_t k : comp.branches) current[k] = comp.x[branch_row_[k]];
  }
}

std::vector<bool> edges_on_cycles(std::uint32_t node_count,
                                  std::span<const std::pair<std::uint32_t, std::uint32_t>> edges) {
  std::vector<bool> on_cycle(edges.size(), false);
  // Adjacency as CSR: (neighbour, edge id). Self-loops are cycles by themselves
  // and play no part in the lowlink computation.
  std::vector<std::uint32_t> start(node_count + 1, 0);
  for (const auto& [a, b] : edges)
    if (a != b) ++start[a + 1], ++start[b + 1];
  for (std::uint32_t v = 0; v < node_count; ++v) start[v + 1] += start[v];
  std::vector<std::pair<std::uint32_t, std::uint32_t>> adj(start[node_count]);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::uint32_t i = 0; i < edges.size(); ++i) {
    const auto [a, b] = edges[i];
    if (a == b) {
      on_cycle[i] = true;
      continue;
    }
    adj[fill[a]++] = {b, i};
    adj[fill[b]++] = {a, i};
  }

  constexpr std::uint32_t kUnseen = 0xffffffffu;
  std::vector<std::uint32_t> disc(node_count, kUnseen), low(node_count, 0);
  struct Frame {
    std::uint32_t node, parent_edge, next;
  };
  std::vector<Frame> stack;
  std::vector<bool> tree(edges.size(), false);
  std::uint32_t time = 0;
  for (std::uint32_t root = 0; root < node_count; ++root) {
    if (disc[root] != kUnseen) continue;
    disc[root] = low[root] = time++;
    stack.push_back({root, kUnseen, start[root]});
    while (!stack.empty()) {
      Frame& f = stack.back();
      if (f.next < start[f.node + 1]) {
        const auto [w, id] = adj[f.next++];
        if (id == f.parent_edge) continue;  // the tree edge we came by (not a parallel twin)
        if (disc[w] == kUnseen) {
          disc[w] = low[w] = time++;
          tree[id] = true;
          stack.push_back({w, id, start[w]});
        } else {
          low[f.node] = std::min(low[f.node], disc[w]);
        }
        continue;
      }
      // f.node is finished: hand its lowlink to its parent and judge the tree edge.
      const Frame done = f;
      stack.pop_back();
      if (stack.empty()) break;
      const std::uint32_t parent = stack.back().node;
      low[parent] = std::min(low[parent], low[done.node]);
      // The tree edge parent-child is a bridge iff nothing below the child
      // reaches the parent or above by another edge.
      on_cycle[done.parent_edge] = low[done.node] <= disc[parent];
    }
  }
  // Every edge that is not a tree edge closes a cycle with the tree path between its ends.
  for (std::uint32_t i = 0; i < edges.size(); ++i)
    if (!tree[i]) on_cycle[i] = true;
  return on_cycle;
}

}  // namespace alloy::electricity
