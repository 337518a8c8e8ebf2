#include "resolvers/common/fmm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "resolvers/common/direct_kernel.hpp"

namespace alloy::multipole {

namespace {
// Below this a cube is not split further, whatever it holds: atoms at one
// point (or nearly) would otherwise recurse without end.
constexpr int kMaxDepth = 40;
}  // namespace

void Fmm::make_tables(int p) {
  if (p == order_) return;
  order_ = p;
  const int side = p + 1;
  index_.assign(std::size_t(side) * side * side, -1);
  ia_.clear(), ib_.clear(), ic_.clear(), deg_.clear();
  for (int n = 0; n <= p; ++n)
    for (int a = n; a >= 0; --a)
      for (int b = n - a; b >= 0; --b) {
        const int c = n - a - b;
        index_[(a * side + b) * side + c] = std::int32_t(ia_.size());
        ia_.push_back(std::uint8_t(a)), ib_.push_back(std::uint8_t(b)),
            ic_.push_back(std::uint8_t(c)), deg_.push_back(std::uint8_t(n));
      }
  nterms_ = int(ia_.size());
  offset_.resize(nterms_);
  for (int t = 0; t < nterms_; ++t) offset_[t] = (ia_[t] * side + ib_[t]) * side + ic_[t];
  prefix_.assign(std::size_t(p) + 1, 0);  // terms of degree <= n: the first prefix_[n]
  for (int t = 0; t < nterms_; ++t)
    for (int n = deg_[t]; n <= p; ++n) ++prefix_[std::size_t(n)];
  auto idx = [&](int a, int b, int c) {
    return (a < 0 || b < 0 || c < 0 || a + b + c > p) ? -1 : index_[(a * side + b) * side + c];
  };
  auto fact = [](int k) {
    double f = 1;
    for (int i = 2; i <= k; ++i) f *= i;
    return f;
  };
  inv_fact_.resize(nterms_), dx_.resize(nterms_), dy_.resize(nterms_), dz_.resize(nterms_);
  rec_axis_.resize(nterms_), rec_prev_.resize(nterms_), rec_prev2_.resize(nterms_);
  rec_k_.resize(nterms_);
  for (int t = 0; t < nterms_; ++t) {
    const int a = ia_[t], b = ib_[t], c = ic_[t];
    inv_fact_[t] = 1.0 / (fact(a) * fact(b) * fact(c));
    dx_[t] = idx(a - 1, b, c), dy_[t] = idx(a, b - 1, c), dz_[t] = idx(a, b, c - 1);
    // D^(j)_{..., e+1, ...} = X D^(j+1)_{..., e, ...} + e D^(j+1)_{..., e-1, ...}
    // along the first axis with a nonzero exponent.
    if (t == 0) {
      rec_axis_[t] = -1, rec_prev_[t] = rec_prev2_[t] = -1, rec_k_[t] = 0;
    } else if (a > 0) {
      rec_axis_[t] = 0, rec_prev_[t] = idx(a - 1, b, c), rec_prev2_[t] = idx(a - 2, b, c),
      rec_k_[t] = a - 1;
    } else if (b > 0) {
      rec_axis_[t] = 1, rec_prev_[t] = idx(a, b - 1, c), rec_prev2_[t] = idx(a, b - 2, c),
      rec_k_[t] = b - 1;
    } else {
      rec_axis_[t] = 2, rec_prev_[t] = idx(a, b, c - 1), rec_prev2_[t] = idx(a, b, c - 2),
      rec_k_[t] = c - 1;
    }
  }
  m2m_terms_.clear(), l2l_terms_.clear(), l2l_coef_.clear();
  for (int to = 0; to < nterms_; ++to)
    for (int from = 0; from < nterms_; ++from) {
      const int pa = ia_[to] - ia_[from], pb = ib_[to] - ib_[from], pc = ic_[to] - ic_[from];
      if (pa < 0 || pb < 0 || pc < 0) continue;
      // M2M: M_parent[to] += M_child[from] s^(to-from) / (to-from)!
      m2m_terms_.push_back({to, from, idx(pa, pb, pc)});
      // L2L: L_child[from] += L_parent[to] C(to, from) t^(to-from)
      //    = L_parent[to] (to! / from!) t^(to-from) / (to-from)!
      l2l_terms_.push_back({from, to, idx(pa, pb, pc)});
      l2l_coef_.push_back(inv_fact_[from] / inv_fact_[to]);
    }
}

void Fmm::build(std::span<const Source> sources, double softening, FmmOptions options) {
  eps2_ = softening * softening;
  theta_ = std::clamp(options.theta, 1e-3, 0.99);
  leaf_size_ = std::max<std::uint32_t>(1, options.leaf_size);
  make_tables(std::clamp(options.order, 1, kMaxFmmOrder));
  nodes_.clear();
  atoms_.clear();
  const auto n = std::uint32_t(sources.size());
  src_.clear();
  order_of_.clear();
  if (n == 0) return;

  // Atoms: a group's sources together, or one ungrouped source.
  std::uint32_t groups = 0;
  for (const Source& s : sources)
    if (s.group != kNoGroup) groups = std::max(groups, s.group + 1);
  std::vector<std::uint32_t> start(groups + 1, 0);
  for (const Source& s : sources)
    if (s.group != kNoGroup) ++start[s.group + 1];
  for (std::uint32_t g = 0; g < groups; ++g) start[g + 1] += start[g];
  atom_members_.resize(n);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    std::uint32_t loose = start[groups];
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t g = sources[i].group;
      atom_members_[g == kNoGroup ? loose++ : fill[g]++] = i;
    }
  }
  for (std::uint32_t g = 0; g < groups; ++g)
    if (start[g + 1] > start[g]) atoms_.push_back({{}, start[g], start[g + 1] - start[g]});
  for (std::uint32_t k = start[groups]; k < n; ++k) atoms_.push_back({{}, k, 1});
  for (Atom& a : atoms_) {
    Vec3 c{};
    for (std::uint32_t k = a.first; k < a.first + a.count; ++k)
      c += sources[atom_members_[k]].position;
    a.centre = c / double(a.count);
  }

  const auto na = std::uint32_t(atoms_.size());
  Vec3 lo = atoms_[0].centre, hi = lo;
  for (const Atom& a : atoms_) {
    lo = {std::min(lo.x, a.centre.x), std::min(lo.y, a.centre.y), std::min(lo.z, a.centre.z)};
    hi = {std::max(hi.x, a.centre.x), std::max(hi.y, a.centre.y), std::max(hi.z, a.centre.z)};
  }
  const Vec3 mid = (lo + hi) * 0.5;
  const double half = 0.5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) * (1 + 1e-9) + 1e-12;
  atom_order_.resize(na);
  for (std::uint32_t i = 0; i < na; ++i) atom_order_[i] = i;
  scratch_.resize(na);
  nodes_.reserve(2 * (na / std::max<std::uint32_t>(1, leaf_size_ / 2) + 1));
  nodes_.emplace_back();
  nodes_[0].begin = 0, nodes_[0].end = na;
  make_node(mid, half, 0, na, 0, 0);

  // Sources in tree order; node ranges from atom positions to source positions.
  std::vector<std::uint32_t> atom_start(na + 1, 0);
  src_.reserve(n);
  order_of_.reserve(n);
  for (std::uint32_t pos = 0; pos < na; ++pos) {
    const Atom& a = atoms_[atom_order_[pos]];
    atom_start[pos] = std::uint32_t(src_.size());
    for (std::uint32_t k = a.first; k < a.first + a.count; ++k) {
      src_.push_back(sources[atom_members_[k]]);
      order_of_.push_back(atom_members_[k]);
    }
  }
  atom_start[na] = n;
  for (Node& node : nodes_) node.begin = atom_start[node.begin], node.end = atom_start[node.end];

  sx_.resize(n), sy_.resize(n), sz_.resize(n), sq_.resize(n), sg_.resize(n), tg_.resize(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const Source& s = src_[t];
    sx_[t] = s.position.x, sy_[t] = s.position.y, sz_[t] = s.position.z, sq_[t] = s.strength;
    sg_[t] = s.group == kNoGroup ? -1.0 : double(s.group);
    tg_[t] = s.group == kNoGroup ? -2.0 : double(s.group);
  }
  upward();
}

// Splits node `index` (its begin/end are atom positions) into its non-empty
// octants, allocated as one block of consecutive nodes, and recurses.
std::int32_t Fmm::make_node(Vec3 box_centre, double half, std::uint32_t begin, std::uint32_t end,
                            int depth, std::int32_t index) {
  std::uint32_t count = 0;
  for (std::uint32_t p = begin; p < end; ++p) count += atoms_[atom_order_[p]].count;
  if (count <= leaf_size_ || end - begin <= 1 || depth >= kMaxDepth) return index;

  auto octant = [&](std::uint32_t a) {
    const Vec3 p = atoms_[a].centre;
    return int(p.x >= box_centre.x) | int(p.y >= box_centre.y) << 1 | int(p.z >= box_centre.z) << 2;
  };
  std::uint32_t bucket[9] = {};
  for (std::uint32_t t = begin; t < end; ++t) ++bucket[octant(atom_order_[t]) + 1];
  for (int o = 0; o < 8; ++o) bucket[o + 1] += bucket[o];
  std::uint32_t next[8];
  for (int o = 0; o < 8; ++o) next[o] = begin + bucket[o];
  for (std::uint32_t t = begin; t < end; ++t)
    scratch_[next[octant(atom_order_[t])]++] = atom_order_[t];
  std::copy(scratch_.begin() + begin, scratch_.begin() + end, atom_order_.begin() + begin);

  const auto first = std::int32_t(nodes_.size());
  int made = 0;
  for (int o = 0; o < 8; ++o) {
    if (bucket[o] == bucket[o + 1]) continue;
    Node child;
    child.begin = begin + bucket[o], child.end = begin + bucket[o + 1];
    child.parent = index;
    nodes_.push_back(child);
    ++made;
  }
  nodes_[index].first_child = first;
  nodes_[index].children = made;
  const double h = 0.5 * half;
  int k = 0;
  for (int o = 0; o < 8; ++o) {
    if (bucket[o] == bucket[o + 1]) continue;
    const Vec3 c{box_centre.x + ((o & 1) ? h : -h), box_centre.y + ((o & 2) ? h : -h),
                 box_centre.z + ((o & 4) ? h : -h)};
    make_node(c, h, begin + bucket[o], begin + bucket[o + 1], depth + 1, first + k);
    ++k;
  }
  return index;
}

// Centres, radii and multipole moments, leaves from their sources (P2M) and
// the rest from their children (M2M), children before parents.
void Fmm::upward() {
  const std::size_t nt = std::size_t(nterms_);
  mult_.assign(nodes_.size() * nt, 0.0);
  std::vector<double> pw(nt);
  auto powers = [&](Vec3 s, double* out) {  // out[t] = s^t / t!
    out[0] = 1;
    for (int t = 1; t < nterms_; ++t) {
      if (ia_[t] > 0)
        out[t] = out[dx_[t]] * s.x / ia_[t];
      else if (ib_[t] > 0)
        out[t] = out[dy_[t]] * s.y / ib_[t];
      else
        out[t] = out[dz_[t]] * s.z / ic_[t];
    }
  };
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    Node& node = nodes_[k];
    double w = 0;
    Vec3 c{}, plain{};
    for (std::uint32_t t = node.begin; t < node.end; ++t) {
      const double a = std::abs(src_[t].strength);
      w += a;
      c += src_[t].position * a;
      plain += src_[t].position;
    }
    node.empty = !(w > 0);
    // A cell without strength still holds targets: centre it on its sources.
    node.centre = node.empty ? plain / double(node.end - node.begin) : c / w;
    double r2 = 0;
    for (std::uint32_t t = node.begin; t < node.end; ++t) {
      const Vec3 d = src_[t].position - node.centre;
      r2 = std::max(r2, dot(d, d));
    }
    node.radius = std::sqrt(r2);
    double* m = mult_.data() + k * nt;
    if (node.empty) continue;
    if (node.children == 0) {
      for (std::uint32_t t = node.begin; t < node.end; ++t) {
        if (src_[t].strength == 0) continue;
        powers(src_[t].position - node.centre, pw.data());
        for (std::size_t i = 0; i < nt; ++i) m[i] += src_[t].strength * pw[i];
      }
    } else {
      for (std::int32_t ch = node.first_child; ch < node.first_child + node.children; ++ch) {
        if (nodes_[ch].empty) continue;
        powers(nodes_[ch].centre - node.centre, pw.data());
        const double* mc = mult_.data() + std::size_t(ch) * nt;
        for (const ShiftTerm& s : m2m_terms_) m[s.to] += mc[s.from] * pw[s.power];
      }
    }
  }
  mneg_.resize(mult_.size());
  for (std::size_t i = 0; i < mult_.size(); ++i)
    mneg_[i] = (deg_[i % nt] & 1) ? -mult_[i] : mult_[i];
}

// The multi-indices of order P as compile-time tables, in the order
// make_tables() numbers them (total degree up, then a down, then b down), so
// that the translations below unroll into straight-line code with constant
// offsets (the table-driven loop spent most of its time on the indices).
template <int P>
constexpr int N_of() {
  return (P + 1) * (P + 2) * (P + 3) / 6;
}
template <int P>
struct Terms {
  static constexpr int N = (P + 1) * (P + 2) * (P + 3) / 6;
  std::array<int, N> deg{}, off{};
  std::array<int, P + 1> prefix{};  ///< terms of degree <= n
  /// The derivative recurrence (Fmm::make_tables): axis, the terms one and
  /// two steps back along it (-1: none) and the second one's factor.
  std::array<int, N> axis{}, prev{}, prev2{}, k{};
};
template <int P>
constexpr Terms<P> make_terms() {
  Terms<P> t;
  int i = 0;
  for (int n = 0; n <= P; ++n) {
    for (int a = n; a >= 0; --a)
      for (int b = n - a; b >= 0; --b) {
        const int c = n - a - b;
        t.deg[i] = n;
        t.off[i] = (a * (P + 1) + b) * (P + 1) + c;
        ++i;
      }
    t.prefix[n] = i;
  }
  auto find = [&](int a, int b, int c) {
    if (a < 0 || b < 0 || c < 0) return -1;
    for (int j = 0; j < N_of<P>(); ++j)
      if (t.off[j] == (a * (P + 1) + b) * (P + 1) + c) return j;
    return -1;
  };
  for (int j = 0; j < t.N; ++j) {
    const int o = t.off[j], a = o / ((P + 1) * (P + 1)), b = o / (P + 1) % (P + 1), c = o % (P + 1);
    t.axis[j] = a > 0 ? 0 : b > 0 ? 1 : 2;
    const int da = t.axis[j] == 0, db = t.axis[j] == 1, dc = t.axis[j] == 2;
    t.prev[j] = find(a - da, b - db, c - dc);
    t.prev2[j] = find(a - 2 * da, b - 2 * db, c - 2 * dc);
    t.k[j] = (a > 0 ? a : b > 0 ? b : c) - 1;
  }
  return t;
}

// The derivatives D_n(r) of G = 1/s, s^2 = |r|^2 + eps^2, for |n| <= P, into
// the dense arrays of contract_fixed: dpos[offset(n)] = D_n(r), dneg the same
// at -r. Through g_j = (d/du)^j G with u = |r|^2 / 2 (g_j = -(2j - 1)
// g_(j-1) / s^2) and D^(j)_(e+1) = X D^(j+1)_e + e D^(j+1)_(e-1) along one axis;
// unrolled for the fixed P.
template <int P>
void derivatives_fixed(Vec3 r, double eps2, double* __restrict dpos, double* __restrict dneg) {
  static constexpr Terms<P> T = make_terms<P>();
  double aux[T.N][P + 1];
  const double inv_s2 = 1.0 / (dot(r, r) + eps2);
  aux[0][0] = std::sqrt(inv_s2);
#pragma GCC unroll 16
  for (int j = 1; j <= P; ++j) aux[0][j] = -(2 * j - 1) * aux[0][j - 1] * inv_s2;
  const double xyz[3] = {r.x, r.y, r.z};
#pragma GCC unroll 200
  for (int t = 1; t < T.N; ++t) {
    const double X = xyz[T.axis[t]];
#pragma GCC unroll 16
    for (int j = 0; j < P; ++j) {
      if (j > P - T.deg[t]) continue;  // a constant once unrolled
      const double back2 =
          T.prev2[t] >= 0 ? T.k[t] * aux[T.prev2[t] < 0 ? 0 : T.prev2[t]][j + 1] : 0.0;
      aux[t][j] = X * aux[T.prev[t]][j + 1] + back2;
    }
  }
#pragma GCC unroll 200
  for (int t = 0; t < T.N; ++t) {
    dpos[T.off[t]] = aux[t][0];
    dneg[T.off[t]] = (T.deg[t] & 1) ? -aux[t][0] : aux[t][0];
  }
}

// u[m] += sum over k with |k| <= p - |m| of mn[k] d[offset(m) + offset(k)],
// as one list of (m, k, offset) of constant length that the compiler unrolls.
template <int P>
struct Pairs {
  static constexpr int count() {
    constexpr Terms<P> T = make_terms<P>();
    int c = 0;
    for (int m = 0; m < T.N; ++m) c += T.prefix[P - T.deg[m]];
    return c;
  }
  std::array<std::array<int, 3>, count()> e{};
};
template <int P>
constexpr Pairs<P> make_pairs() {
  constexpr Terms<P> T = make_terms<P>();
  Pairs<P> p;
  int i = 0;
  for (int m = 0; m < T.N; ++m)
    for (int k = 0; k < T.prefix[P - T.deg[m]]; ++k) p.e[i++] = {m, k, T.off[m] + T.off[k]};
  return p;
}
template <int P>
void contract_fixed(const double* __restrict mn, const double* __restrict d, double* __restrict u) {
  static constexpr Pairs<P> L = make_pairs<P>();
#pragma GCC unroll 1024
  for (int i = 0; i < int(L.e.size()); ++i) u[L.e[i][0]] += mn[L.e[i][1]] * d[L.e[i][2]];
}

void Fmm::contract(const double* mn, const double* d, double* u) const {
  switch (order_) {
    case 1:
      return contract_fixed<1>(mn, d, u);
    case 2:
      return contract_fixed<2>(mn, d, u);
    case 3:
      return contract_fixed<3>(mn, d, u);
    case 4:
      return contract_fixed<4>(mn, d, u);
    case 5:
      return contract_fixed<5>(mn, d, u);
    default:
      return contract_fixed<6>(mn, d, u);
  }
}

void Fmm::m2l(std::int32_t a, std::int32_t b) {
  const std::size_t nt = std::size_t(nterms_);
  const Vec3 r = nodes_[a].centre - nodes_[b].centre;
  // U_A[m] += sum_k (-1)^|k| M_B[k] D_(k+m)(r), and B's the same with r -> -r
  // (D_n(-r) = (-1)^|n| D_n(r)); the 1/m! of the local expansion is applied
  // once, before the downward pass. D in a dense (p+1)^3 array, so that the
  // term k + m sits at offset(k) + offset(m).
  double dpos[(kMaxFmmOrder + 1) * (kMaxFmmOrder + 1) * (kMaxFmmOrder + 1)];
  double dneg[(kMaxFmmOrder + 1) * (kMaxFmmOrder + 1) * (kMaxFmmOrder + 1)];
  switch (order_) {
    case 1:
      derivatives_fixed<1>(r, eps2_, dpos, dneg);
      break;
    case 2:
      derivatives_fixed<2>(r, eps2_, dpos, dneg);
      break;
    case 3:
      derivatives_fixed<3>(r, eps2_, dpos, dneg);
      break;
    case 4:
      derivatives_fixed<4>(r, eps2_, dpos, dneg);
      break;
    case 5:
      derivatives_fixed<5>(r, eps2_, dpos, dneg);
      break;
    default:
      derivatives_fixed<6>(r, eps2_, dpos, dneg);
      break;
  }
  const bool to_a = !nodes_[b].empty, to_b = !nodes_[a].empty;
  if (to_a) contract(mneg_.data() + std::size_t(b) * nt, dpos, local_.data() + std::size_t(a) * nt);
  if (to_b) contract(mneg_.data() + std::size_t(a) * nt, dneg, local_.data() + std::size_t(b) * nt);
  ++m2l_;
}

// The near field of one cell (a leaf, or a small cell summed whole): the
// sources of its near cells (itself among them, for a leaf) gathered into one
// run, so that the SIMD kernel reduces each target's lanes once, not once per
// cell (small cells would otherwise spend their time in the reductions).
void Fmm::near_field(const Node& leaf, std::span<const std::int32_t> near) {
  nx_.clear(), ny_.clear(), nz_.clear(), nq_.clear(), ng_.clear();
  std::uint32_t run_begin = 0, run_end = 0;
  auto take = [&] {
    nx_.insert(nx_.end(), sx_.begin() + run_begin, sx_.begin() + run_end);
    ny_.insert(ny_.end(), sy_.begin() + run_begin, sy_.begin() + run_end);
    nz_.insert(nz_.end(), sz_.begin() + run_begin, sz_.begin() + run_end);
    nq_.insert(nq_.end(), sq_.begin() + run_begin, sq_.begin() + run_end);
    ng_.insert(ng_.end(), sg_.begin() + run_begin, sg_.begin() + run_end);
  };
  for (std::int32_t k : near) {
    const Node& b = nodes_[std::size_t(k)];
    if (b.empty) continue;
    if (b.begin == run_end) {
      run_end = b.end;  // neighbours in memory: one run
    } else {
      take();
      run_begin = b.begin, run_end = b.end;
    }
  }
  take();
  const std::uint32_t n = leaf.end - leaf.begin;
  direct_accumulate({sx_.data() + leaf.begin, sy_.data() + leaf.begin, sz_.data() + leaf.begin,
                     tg_.data() + leaf.begin, fx_.data() + leaf.begin, fy_.data() + leaf.begin,
                     fz_.data() + leaf.begin, n},
                    {nx_.data(), ny_.data(), nz_.data(), nq_.data(), ng_.data(), nx_.size()},
                    eps2_);
  p2p_ += std::uint64_t(n) * nx_.size();
}

void Fmm::evaluate_at_sources(std::span<Vec3> out) {
  const std::size_t n = src_.size();
  if (n == 0) return;
  if (out.size() != n) throw std::invalid_argument("Fmm::evaluate_at_sources: wrong output size");
  const std::size_t nt = std::size_t(nterms_);
  local_.assign(nodes_.size() * nt, 0.0);
  fx_.assign(n, 0.0), fy_.assign(n, 0.0), fz_.assign(n, 0.0);

  // The dual-tree walk: every pair of cells is either separated (M2L both
  // ways), two leaves (direct both ways), or split at its larger cell.
  const double theta2 = theta_ * theta_;
  const std::uint64_t direct_pairs = std::uint64_t(leaf_size_) * leaf_size_;
  stack_.clear();
  near_pairs_.clear();
  stack_.emplace_back(0, 0);
  while (!stack_.empty()) {
    const auto [a, b] = stack_.back();
    stack_.pop_back();
    const Node& A = nodes_[a];
    if (a == b) {
      if (A.children == 0) {
        near_pairs_.emplace_back(a, a);
        continue;
      }
      for (std::int32_t i = A.first_child; i < A.first_child + A.children; ++i)
        for (std::int32_t j = i; j < A.first_child + A.children; ++j) stack_.emplace_back(i, j);
      continue;
    }
    const Node& B = nodes_[b];
    if (A.empty && B.empty) continue;
    const Vec3 gap = A.centre - B.centre;
    const double reach = A.radius + B.radius;
    if (reach * reach < theta2 * dot(gap, gap)) {
      m2l(a, b);
    } else if ((A.children == 0 && B.children == 0) ||
               std::uint64_t(A.end - A.begin) * (B.end - B.begin) <= direct_pairs) {
      // Two leaves, or two cells so small that their pairs cost less than
      // splitting them into many small translations: summed directly.
      near_pairs_.emplace_back(a, b);
      near_pairs_.emplace_back(b, a);
    } else if (B.children == 0 || (A.children != 0 && A.radius >= B.radius)) {
      for (std::int32_t i = A.first_child; i < A.first_child + A.children; ++i)
        stack_.emplace_back(i, b);
    } else {
      for (std::int32_t j = B.first_child; j < B.first_child + B.children; ++j)
        stack_.emplace_back(a, j);
    }
  }

  // The near field, leaf by leaf (target leaf, then its near leaves in
  // memory order: a fixed order, so fixed bits).
  std::sort(near_pairs_.begin(), near_pairs_.end());
  near_list_.clear();
  for (std::size_t i = 0; i < near_pairs_.size();) {
    std::size_t j = i;
    near_list_.clear();
    while (j < near_pairs_.size() && near_pairs_[j].first == near_pairs_[i].first)
      near_list_.push_back(near_pairs_[j++].second);
    near_field(nodes_[std::size_t(near_pairs_[i].first)], near_list_);
    i = j;
  }

  // The translations summed U[m] = m! L[m].
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    for (std::size_t m = 0; m < nt; ++m) local_[k * nt + m] *= inv_fact_[m];
  // Down: each cell's local expansion moved to its children's centres (L2L),
  // parents first (a parent's index is below its children's).
  std::vector<double> pw(nt);
  auto powers = [&](Vec3 s, double* o) {  // o[t] = s^t / t!
    o[0] = 1;
    for (int t = 1; t < nterms_; ++t) {
      if (ia_[t] > 0)
        o[t] = o[dx_[t]] * s.x / ia_[t];
      else if (ib_[t] > 0)
        o[t] = o[dy_[t]] * s.y / ib_[t];
      else
        o[t] = o[dz_[t]] * s.z / ic_[t];
    }
  };
  for (std::size_t k = 1; k < nodes_.size(); ++k) {
    const Node& node = nodes_[k];
    powers(node.centre - nodes_[std::size_t(node.parent)].centre, pw.data());
    const double* lp = local_.data() + std::size_t(node.parent) * nt;
    double* lc = local_.data() + k * nt;
    for (std::size_t e = 0; e < l2l_terms_.size(); ++e) {
      const ShiftTerm& s = l2l_terms_[e];
      lc[s.to] += l2l_coef_[e] * lp[s.from] * pw[s.power];
    }
  }
  // At the leaves' sources: F = -grad phi, phi(c + y) = sum_m L_m y^m.
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const Node& node = nodes_[k];
    if (node.children != 0) continue;
    const double* l = local_.data() + k * nt;
    for (std::uint32_t t = node.begin; t < node.end; ++t) {
      const Vec3 y = src_[t].position - node.centre;
      powers(y, pw.data());  // y^m / m!: times m! below
      double gx = 0, gy = 0, gz = 0;
      for (int m = 1; m < nterms_; ++m) {
        // d/dy_x of y^m = a y^(m - x): term dx_[m] of pw, times its factorial.
        if (ia_[m] > 0) gx += l[m] * ia_[m] * pw[dx_[m]] / inv_fact_[dx_[m]];
        if (ib_[m] > 0) gy += l[m] * ib_[m] * pw[dy_[m]] / inv_fact_[dy_[m]];
        if (ic_[m] > 0) gz += l[m] * ic_[m] * pw[dz_[m]] / inv_fact_[dz_[m]];
      }
      fx_[t] -= gx, fy_[t] -= gy, fz_[t] -= gz;
    }
  }
  for (std::size_t t = 0; t < n; ++t) out[order_of_[t]] = {fx_[t], fy_[t], fz_[t]};
}

}  // namespace alloy::multipole
