#include "resolvers/common/fmm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "resolvers/common/direct_kernel.hpp"

namespace alloy::multipole {

namespace {

/// Appends the source range [begin, end) to `runs`, joining it to the last
/// run when they are neighbours in memory (one run for both).
void add_run(std::vector<std::pair<std::uint32_t, std::uint32_t>>& runs, std::uint32_t begin,
             std::uint32_t end) {
  if (!runs.empty() && runs.back().second == begin)
    runs.back().second = end;
  else
    runs.emplace_back(begin, end);
}

// Below this a cube is not split further, whatever it holds: atoms at one
// point (or nearly) would otherwise recurse without end.
constexpr int kMaxDepth = 40;

// The calling thread's CPU time: the profile stays meaningful on a loaded
// machine (the bench runs beside other work).
double seconds_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
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
  rcp_.assign(nterms_, 0.0);
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
  for (int t = 1; t < nterms_; ++t) rcp_[t] = 1.0 / (rec_k_[t] + 1);
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
  const double t0 = seconds_now();
  eps2_ = softening * softening;
  theta_ = std::clamp(options.theta, 1e-3, 0.99);
  leaf_size_ = std::max<std::uint32_t>(1, options.leaf_size);
  options_vector_m2l_ = int(options.m2l);
  mutual_near_ = options.mutual_near;
  single_near_ = options.single_near && softening > 0;
  make_tables(std::clamp(options.order, 1, kMaxFmmOrder));
  // rho^(q-1) <= theta^(p-1)  <=>  rho^2 <= theta^(2 (p-1) / (q-1)), for
  // 2 <= q < p (q = p needs no limit: the walk's theta rule is it; order 1
  // drops a dipole's field altogether, so never: limit -1).
  pair_orders_ = options.pair_orders;
  for (int q = 1; q <= kMaxFmmOrder; ++q)
    order_limit2_[std::size_t(q)] =
        q < 2 || order_ < 2 ? -1.0 : std::pow(theta_, 2.0 * (order_ - 1) / (q - 1));
  reused_ = options.reuse && try_reuse(sources);
  if (reused_) {
    profile_.upward += seconds_now() - t0;
    return;
  }
  lists_valid_ = false;
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
  integer_groups();
  const double t1 = seconds_now();
  upward();
  built_leaf_ = leaf_size_, built_eps2_ = eps2_;
  built_radius_.resize(nodes_.size()), built_empty_.resize(nodes_.size());
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    built_radius_[k] = nodes_[k].radius, built_empty_[k] = nodes_[k].empty;
  built_root_radius_ = nodes_.empty() ? 0 : nodes_[0].radius;
  profile_.tree += t1 - t0;
  profile_.upward += seconds_now() - t1;
}

// Groups as 32-bit integers for the float kernels; a group number that does
// not fit leaves the near field in double.
void Fmm::integer_groups() {
  if (!single_near_) return;
  const std::size_t n = src_.size();
  sgi_.resize(n), tgi_.resize(n);
  for (std::size_t t = 0; t < n && single_near_; ++t) {
    const std::uint32_t g = src_[t].group;
    if (g != kNoGroup && g > 0x7fffffffu) single_near_ = false;
    sgi_[t] = g == kNoGroup ? -1 : std::int32_t(g);
    tgi_[t] = g == kNoGroup ? -2 : std::int32_t(g);
  }
}

// FmmOptions::reuse: the same sources (count, groups, in the order given)
// under the same leaves and softening as the last full build: refresh the
// sources in tree order and the upward pass, keep the cells. False (for a
// full build) when a cell grew past 1.5 times its radius then, or a cell's
// emptiness changed (the walk skips pairs of empty cells).
bool Fmm::try_reuse(std::span<const Source> sources) {
  const std::size_t n = sources.size();
  if (nodes_.empty() || n != src_.size() || built_leaf_ != leaf_size_ || built_eps2_ != eps2_)
    return false;
  for (std::size_t t = 0; t < n; ++t)
    if (sources[order_of_[t]].group != src_[t].group) return false;
  for (std::size_t t = 0; t < n; ++t) {
    const Source& s = sources[order_of_[t]];
    src_[t] = s;
    sx_[t] = s.position.x, sy_[t] = s.position.y, sz_[t] = s.position.z, sq_[t] = s.strength;
  }
  integer_groups();
  upward();
  const double slack = 1e-3 * built_root_radius_;
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    if (nodes_[k].radius > 1.5 * built_radius_[k] + slack ||
        bool(built_empty_[k]) != nodes_[k].empty)
      return false;
  return true;
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

// out[t] = s^t / t!, each term from the one a step back along its axis, times
// the coordinate and a reciprocal from the table (no division).
void Fmm::scaled_powers(Vec3 s, double* out) const {
  const double xyz[3] = {s.x, s.y, s.z};
  out[0] = 1;
  for (int t = 1; t < nterms_; ++t)
    out[t] = out[rec_prev_[std::size_t(t)]] * xyz[rec_axis_[std::size_t(t)]] * rcp_[std::size_t(t)];
}

// P2M at one leaf and L2P at one leaf's sources, unrolled for the order
// (defined below, after the compile-time term tables).
void p2m_leaf(int order, const double* x, const double* y, const double* z, const double* q,
              std::uint32_t begin, std::uint32_t end, Vec3 c, double* m);
void l2p_leaf(int order, const double* l, const double* x, const double* y, const double* z,
              std::uint32_t begin, std::uint32_t end, Vec3 c, double* fx, double* fy, double* fz);

// Centres, radii and multipole moments, leaves from their sources (P2M) and
// the rest from their children (M2M), children before parents.
void Fmm::upward() {
  const std::size_t nt = std::size_t(nterms_);
  mult_.assign(nodes_.size() * nt, 0.0);
  std::vector<double> pw(nt);
  auto powers = [&](Vec3 v, double* out) { scaled_powers(v, out); };
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
      p2m_leaf(order_, sx_.data(), sy_.data(), sz_.data(), sq_.data(), node.begin, node.end,
               node.centre, m);
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

// The translations below are unrolled whole for speed. Under the address
// sanitizer that straight-line code, instrumented, took clang more than
// twenty minutes and 2 GB to compile (fmm.cpp alone), so a sanitizer build
// leaves the loops to the compiler: the same operations in the same order,
// so the same bits.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ALLOY_FMM_SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define ALLOY_FMM_SANITIZED 1
#endif
#if defined(ALLOY_FMM_SANITIZED)
#define ALLOY_UNROLL(n)
#else
#define ALLOY_UNROLL_TEXT(x) #x
#define ALLOY_UNROLL(n) _Pragma(ALLOY_UNROLL_TEXT(GCC unroll n))
#endif

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
  ALLOY_UNROLL(16)
  for (int j = 1; j <= P; ++j) aux[0][j] = -(2 * j - 1) * aux[0][j - 1] * inv_s2;
  const double xyz[3] = {r.x, r.y, r.z};
  ALLOY_UNROLL(200)
  for (int t = 1; t < T.N; ++t) {
    const double X = xyz[T.axis[t]];
    ALLOY_UNROLL(16)
    for (int j = 0; j < P; ++j) {
      if (j > P - T.deg[t]) continue;  // a constant once unrolled
      const double back2 =
          T.prev2[t] >= 0 ? T.k[t] * aux[T.prev2[t] < 0 ? 0 : T.prev2[t]][j + 1] : 0.0;
      aux[t][j] = X * aux[T.prev[t]][j + 1] + back2;
    }
  }
  ALLOY_UNROLL(200)
  for (int t = 0; t < T.N; ++t) {
    dpos[T.off[t]] = aux[t][0];
    dneg[T.off[t]] = (T.deg[t] & 1) ? -aux[t][0] : aux[t][0];
  }
}

// P2M at a leaf: m[t] += q s^t / t! over its sources, s = x - c, each power
// from the one a step back along its axis times a compile-time reciprocal
// (the same operations, in the same order, as Fmm::scaled_powers).
template <int P>
void p2m_fixed(const double* x, const double* y, const double* z, const double* q,
               std::uint32_t begin, std::uint32_t end, Vec3 c, double* __restrict m) {
  static constexpr Terms<P> T = make_terms<P>();
  for (std::uint32_t t = begin; t < end; ++t) {
    if (q[t] == 0) continue;
    const double xyz[3] = {x[t] - c.x, y[t] - c.y, z[t] - c.z};
    double pw[T.N];
    pw[0] = 1;
    ALLOY_UNROLL(200)
    for (int i = 1; i < T.N; ++i) pw[i] = pw[T.prev[i]] * xyz[T.axis[i]] * (1.0 / (T.k[i] + 1));
    ALLOY_UNROLL(200)
    for (int i = 0; i < T.N; ++i) m[i] += q[t] * pw[i];
  }
}

// L2P at a leaf's sources: F = -grad phi, phi(c + y) = sum_m L_m y^m. The
// gradient's three polynomials (g_x[m - x] = a L_m, and so on) are formed once
// per leaf, then each source takes its plain powers y^t (|t| <= p - 1) and
// three dot products, unrolled.
template <int P>
void l2p_fixed(const double* l, const double* x, const double* y, const double* z,
               std::uint32_t begin, std::uint32_t end, Vec3 c, double* fx, double* fy, double* fz) {
  static constexpr Terms<P> T = make_terms<P>();
  // Per term m and axis: the term m minus one step along it, and the
  // exponent there (0: none).
  struct Down {
    std::array<std::array<int, 3>, T.N> to{}, e{};
  };
  static constexpr Down D = [] {
    Down d;
    auto find = [](int fa, int fb, int fc) {
      for (int j = 0; j < T.N; ++j)
        if (T.off[j] == (fa * (P + 1) + fb) * (P + 1) + fc) return j;
      return 0;
    };
    for (int m = 0; m < T.N; ++m) {
      const int o = T.off[m], a = o / ((P + 1) * (P + 1)), b = o / (P + 1) % (P + 1),
                c = o % (P + 1);
      d.e[m] = {a, b, c};
      d.to[m] = {a > 0 ? find(a - 1, b, c) : 0, b > 0 ? find(a, b - 1, c) : 0,
                 c > 0 ? find(a, b, c - 1) : 0};
    }
    return d;
  }();
  constexpr int G = T.prefix[P - 1];
  double gx[G] = {}, gy[G] = {}, gz[G] = {};
  ALLOY_UNROLL(200)
  for (int m = 1; m < T.N; ++m) {
    if (D.e[m][0] > 0) gx[D.to[m][0]] = l[m] * double(D.e[m][0]);
    if (D.e[m][1] > 0) gy[D.to[m][1]] = l[m] * double(D.e[m][1]);
    if (D.e[m][2] > 0) gz[D.to[m][2]] = l[m] * double(D.e[m][2]);
  }
  for (std::uint32_t t = begin; t < end; ++t) {
    const double xyz[3] = {x[t] - c.x, y[t] - c.y, z[t] - c.z};
    double pw[G];
    pw[0] = 1;
    ALLOY_UNROLL(200)
    for (int m = 1; m < G; ++m) pw[m] = pw[T.prev[m]] * xyz[T.axis[m]];
    double sx = 0, sy = 0, sz = 0;
    ALLOY_UNROLL(200)
    for (int m = 0; m < G; ++m) {
      sx += gx[m] * pw[m];
      sy += gy[m] * pw[m];
      sz += gz[m] * pw[m];
    }
    fx[t] -= sx, fy[t] -= sy, fz[t] -= sz;
  }
}

void p2m_leaf(int order, const double* x, const double* y, const double* z, const double* q,
              std::uint32_t begin, std::uint32_t end, Vec3 c, double* m) {
  switch (order) {
    case 1:
      return p2m_fixed<1>(x, y, z, q, begin, end, c, m);
    case 2:
      return p2m_fixed<2>(x, y, z, q, begin, end, c, m);
    case 3:
      return p2m_fixed<3>(x, y, z, q, begin, end, c, m);
    case 4:
      return p2m_fixed<4>(x, y, z, q, begin, end, c, m);
    case 5:
      return p2m_fixed<5>(x, y, z, q, begin, end, c, m);
    default:
      return p2m_fixed<6>(x, y, z, q, begin, end, c, m);
  }
}

void l2p_leaf(int order, const double* l, const double* x, const double* y, const double* z,
              std::uint32_t begin, std::uint32_t end, Vec3 c, double* fx, double* fy, double* fz) {
  switch (order) {
    case 1:
      return l2p_fixed<1>(l, x, y, z, begin, end, c, fx, fy, fz);
    case 2:
      return l2p_fixed<2>(l, x, y, z, begin, end, c, fx, fy, fz);
    case 3:
      return l2p_fixed<3>(l, x, y, z, begin, end, c, fx, fy, fz);
    case 4:
      return l2p_fixed<4>(l, x, y, z, begin, end, c, fx, fy, fz);
    case 5:
      return l2p_fixed<5>(l, x, y, z, begin, end, c, fx, fy, fz);
    default:
      return l2p_fixed<6>(l, x, y, z, begin, end, c, fx, fy, fz);
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
  ALLOY_UNROLL(1024)
  for (int i = 0; i < int(L.e.size()); ++i) u[L.e[i][0]] += mn[L.e[i][1]] * d[L.e[i][2]];
}

void Fmm::contract(int order, const double* mn, const double* d, double* u) const {
  switch (order) {
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

// --- M2L in batches: several translations at once, one per SIMD lane ---------
//
// The translations of the walk's list are independent, so W of them run side
// by side, each in its own lane: the derivatives of the W separations and the
// two contractions (A from B, B from A) as straight-line code on W-wide
// vectors. The lanes' multipoles are gathered in and their local expansions
// added back lane by lane, in the list's order, so the bits do not depend on
// the batching (a pair's result is computed the same in any lane), only on
// the instruction set (FMA contraction), as for direct_kernel.hpp.
//
// B from A uses the same derivatives: U_B[m] = sum_k (-1)^|k| M_A[k]
// D_(k+m)(-r) = (-1)^|m| sum_k M_A[k] D_(k+m)(r), so the contraction takes A's
// plain moments and the sign is applied on the way out.

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ALLOY_FMM_AVX2 1
typedef double V4d __attribute__((vector_size(32)));
inline double lane(V4d v, int l) {
  return v[l];
}
inline void set_lane(V4d& v, int l, double x) {
  v[l] = x;
}
typedef double V8d __attribute__((vector_size(64)));
inline double lane(V8d v, int l) {
  return v[l];
}
inline void set_lane(V8d& v, int l, double x) {
  v[l] = x;
}
#endif
inline double lane(double v, int) {
  return v;
}
inline void set_lane(double& v, int, double x) {
  v = x;
}

/// What one batch reads and writes: W separations r = c_A - c_B, the moments
/// (A's plain, B's with (-1)^|k|) and the local expansions to add to.
struct M2lBatch {
  Vec3 r[8];
  const double* plain_a[8];
  const double* neg_b[8];
  double* local_a[8];
  double* local_b[8];
};

template <int P, class V, int W>
[[gnu::always_inline]] inline void m2l_lanes(const M2lBatch& in, double eps2) {
  static constexpr Terms<P> T = make_terms<P>();
  static constexpr Pairs<P> L = make_pairs<P>();
  V x{}, y{}, z{};
  for (int l = 0; l < W; ++l)
    set_lane(x, l, in.r[l].x), set_lane(y, l, in.r[l].y), set_lane(z, l, in.r[l].z);
  const V inv_s2 = 1.0 / (x * x + y * y + z * z + eps2);
  V aux[T.N][P + 1];
  V root{};
  for (int l = 0; l < W; ++l) set_lane(root, l, std::sqrt(lane(inv_s2, l)));
  aux[0][0] = root;
  ALLOY_UNROLL(16)
  for (int j = 1; j <= P; ++j) aux[0][j] = -double(2 * j - 1) * aux[0][j - 1] * inv_s2;
  const V xyz[3] = {x, y, z};
  ALLOY_UNROLL(200)
  for (int t = 1; t < T.N; ++t) {
    const V X = xyz[T.axis[t]];
    ALLOY_UNROLL(16)
    for (int j = 0; j < P; ++j) {
      if (j > P - T.deg[t]) continue;  // a constant once unrolled
      if (T.prev2[t] >= 0)
        aux[t][j] = X * aux[T.prev[t]][j + 1] +
                    double(T.k[t]) * aux[T.prev2[t] < 0 ? 0 : T.prev2[t]][j + 1];
      else
        aux[t][j] = X * aux[T.prev[t]][j + 1];
    }
  }
  V d[(P + 1) * (P + 1) * (P + 1)];
  ALLOY_UNROLL(200)
  for (int t = 0; t < T.N; ++t) d[T.off[t]] = aux[t][0];
  V ma[T.N], mb[T.N], ua[T.N], ub[T.N];
  for (int k = 0; k < T.N; ++k) {
    for (int l = 0; l < W; ++l)
      set_lane(ma[k], l, in.plain_a[l][k]), set_lane(mb[k], l, in.neg_b[l][k]);
    ua[k] = V{}, ub[k] = V{};
  }
  ALLOY_UNROLL(1024)
  for (int i = 0; i < int(L.e.size()); ++i) {
    ua[L.e[i][0]] += mb[L.e[i][1]] * d[L.e[i][2]];
    ub[L.e[i][0]] += ma[L.e[i][1]] * d[L.e[i][2]];
  }
  for (int l = 0; l < W; ++l)
    for (int m = 0; m < T.N; ++m) {
      in.local_a[l][m] += lane(ua[m], l);
      in.local_b[l][m] += (T.deg[m] & 1) ? -lane(ub[m], l) : lane(ub[m], l);
    }
}

/// The list's translations, W at a time (the last batch padded with a dummy
/// pair whose moments are zero and whose output goes to `sink`).
struct M2lList {
  const std::pair<std::int32_t, std::int32_t>* pairs;
  std::size_t count;
  const Vec3* centre;
  const double *plain, *neg;
  double* local;
  const double* zero;  ///< nt zeros
  double* sink;        ///< nt doubles, written and ignored
  std::size_t nt;
  double eps2;
};

template <int P, class V, int W>
[[gnu::always_inline]] inline void m2l_run(const M2lList& list) {
  M2lBatch b;
  for (std::size_t i = 0; i < list.count; i += W) {
    for (int l = 0; l < W; ++l) {
      if (i + l < list.count) {
        const auto [a, c] = list.pairs[i + l];
        b.r[l] = list.centre[a] - list.centre[c];
        b.plain_a[l] = list.plain + std::size_t(a) * list.nt;
        b.neg_b[l] = list.neg + std::size_t(c) * list.nt;
        b.local_a[l] = list.local + std::size_t(a) * list.nt;
        b.local_b[l] = list.local + std::size_t(c) * list.nt;
      } else {
        b.r[l] = {1, 0, 0};
        b.plain_a[l] = b.neg_b[l] = list.zero;
        b.local_a[l] = b.local_b[l] = list.sink;
      }
    }
    m2l_lanes<P, V, W>(b, list.eps2);
  }
}

template <int P>
void m2l_run_scalar(const M2lList& list) {
  m2l_run<P, double, 1>(list);
}
#ifdef ALLOY_FMM_AVX2
template <int P>
__attribute__((target("avx2,fma"))) void m2l_run_avx2(const M2lList& list) {
  m2l_run<P, V4d, 4>(list);
}
// Eight lanes where the CPU has AVX-512 (0.8x of the four-lane batches'
// time at order 5, 10,000 magnets; docs/performance.md).
template <int P>
__attribute__((target("avx512f,avx512dq,avx2,fma"))) void m2l_run_avx512(const M2lList& list) {
  m2l_run<P, V8d, 8>(list);
}
#endif

using M2lRunner = void (*)(const M2lList&);
M2lRunner m2l_runner(int order, int width) {
  const bool vector = width > 1;
  static constexpr M2lRunner scalar[] = {m2l_run_scalar<1>, m2l_run_scalar<2>, m2l_run_scalar<3>,
                                         m2l_run_scalar<4>, m2l_run_scalar<5>, m2l_run_scalar<6>};
  const int i = std::clamp(order, 1, kMaxFmmOrder) - 1;
#ifdef ALLOY_FMM_AVX2
  static constexpr M2lRunner avx2[] = {m2l_run_avx2<1>, m2l_run_avx2<2>, m2l_run_avx2<3>,
                                       m2l_run_avx2<4>, m2l_run_avx2<5>, m2l_run_avx2<6>};
  static const bool has_avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  static constexpr M2lRunner avx512[] = {m2l_run_avx512<1>, m2l_run_avx512<2>, m2l_run_avx512<3>,
                                         m2l_run_avx512<4>, m2l_run_avx512<5>, m2l_run_avx512<6>};
  static const bool has_avx512 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  if (width > 4 && has_avx512) return avx512[i];
  if (vector && has_avx2) return avx2[i];
#endif
  (void)vector;
  return scalar[i];
}

void Fmm::m2l(std::int32_t a, std::int32_t b, int order) {
  const std::size_t nt = std::size_t(nterms_);
  const Vec3 r = nodes_[a].centre - nodes_[b].centre;
  // U_A[m] += sum_k (-1)^|k| M_B[k] D_(k+m)(r), and B's the same with r -> -r
  // (D_n(-r) = (-1)^|n| D_n(r)); the 1/m! of the local expansion is applied
  // once, before the downward pass. D in a dense (p+1)^3 array, so that the
  // term k + m sits at offset(k) + offset(m).
  double dpos[(kMaxFmmOrder + 1) * (kMaxFmmOrder + 1) * (kMaxFmmOrder + 1)];
  double dneg[(kMaxFmmOrder + 1) * (kMaxFmmOrder + 1) * (kMaxFmmOrder + 1)];
  switch (order) {
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
  if (to_a)
    contract(order, mneg_.data() + std::size_t(b) * nt, dpos, local_.data() + std::size_t(a) * nt);
  if (to_b)
    contract(order, mneg_.data() + std::size_t(a) * nt, dneg, local_.data() + std::size_t(b) * nt);
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

// The near field of one cell whose pairs with `near` (cells after it, and
// perhaps itself) are each listed once: itself one way (every ordered pair of
// its own sources), the others both ways at once, their sources gathered into
// one run and their sums added back.
void Fmm::near_field_mutual(std::int32_t k, std::span<const std::int32_t> near) {
  if (single_near_ && near_field_single(k, near)) return;
  const Node& leaf = nodes_[std::size_t(k)];
  const std::uint32_t n = leaf.end - leaf.begin;
  const SoaTargets targets{sx_.data() + leaf.begin, sy_.data() + leaf.begin,
                           sz_.data() + leaf.begin, tg_.data() + leaf.begin,
                           fx_.data() + leaf.begin, fy_.data() + leaf.begin,
                           fz_.data() + leaf.begin, n};
  nx_.clear(), ny_.clear(), nz_.clear(), nq_.clear(), ng_.clear(), runs_.clear();
  for (std::int32_t b : near) {
    if (b == k) {
      direct_accumulate(targets,
                        {sx_.data() + leaf.begin, sy_.data() + leaf.begin, sz_.data() + leaf.begin,
                         sq_.data() + leaf.begin, sg_.data() + leaf.begin, n},
                        eps2_);
      p2p_ += std::uint64_t(n) * n;
      continue;
    }
    const Node& B = nodes_[std::size_t(b)];
    add_run(runs_, B.begin, B.end);
  }
  if (runs_.empty()) return;
  for (const auto& [b, e] : runs_) {
    nx_.insert(nx_.end(), sx_.begin() + b, sx_.begin() + e);
    ny_.insert(ny_.end(), sy_.begin() + b, sy_.begin() + e);
    nz_.insert(nz_.end(), sz_.begin() + b, sz_.begin() + e);
    nq_.insert(nq_.end(), sq_.begin() + b, sq_.begin() + e);
    ng_.insert(ng_.end(), sg_.begin() + b, sg_.begin() + e);
  }
  const std::size_t m = nx_.size();
  gx_.assign(m, 0.0), gy_.assign(m, 0.0), gz_.assign(m, 0.0);
  direct_accumulate_mutual(targets, sq_.data() + leaf.begin,
                           {nx_.data(), ny_.data(), nz_.data(), nq_.data(), ng_.data(), m},
                           gx_.data(), gy_.data(), gz_.data(), eps2_);
  std::size_t at = 0;
  for (const auto& [b, e] : runs_)
    for (std::uint32_t t = b; t < e; ++t, ++at)
      fx_[t] += gx_[at], fy_[t] += gy_[at], fz_[t] += gz_[at];
  p2p_ += std::uint64_t(n) * m;
}

// near_field_mutual in single precision: every coordinate relative to the
// leaf's centre, so that float's rounding is relative to the near region's
// size, not to the world's; false (nothing done) when that region spans more
// than kSingleNearReach softening lengths.
bool Fmm::near_field_single(std::int32_t k, std::span<const std::int32_t> near) {
  const Node& leaf = nodes_[std::size_t(k)];
  const Vec3 c = leaf.centre;
  double reach = leaf.radius;
  for (std::int32_t b : near) {
    const Node& B = nodes_[std::size_t(b)];
    reach = std::max(reach, length(B.centre - c) + B.radius);
  }
  if (!(reach * reach <= kSingleNearReach * kSingleNearReach * eps2_)) return false;
  const std::uint32_t n = leaf.end - leaf.begin;
  tfx_.resize(n), tfy_.resize(n), tfz_.resize(n), tfq_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t t = leaf.begin + i;
    tfx_[i] = float(sx_[t] - c.x), tfy_[i] = float(sy_[t] - c.y), tfz_[i] = float(sz_[t] - c.z);
    tfq_[i] = float(sq_[t]);
  }
  const float e2 = float(eps2_);
  const SoaTargetsF targets{tfx_.data(),
                            tfy_.data(),
                            tfz_.data(),
                            tgi_.data() + leaf.begin,
                            fx_.data() + leaf.begin,
                            fy_.data() + leaf.begin,
                            fz_.data() + leaf.begin,
                            n};
  runs_.clear();
  for (std::int32_t b : near) {
    if (b == k) {
      direct_accumulate_single(
          targets,
          {tfx_.data(), tfy_.data(), tfz_.data(), tfq_.data(), sgi_.data() + leaf.begin, n}, e2);
      p2p_ += std::uint64_t(n) * n;
      single_pairs_ += std::uint64_t(n) * n;
      continue;
    }
    const Node& B = nodes_[std::size_t(b)];
    add_run(runs_, B.begin, B.end);
  }
  if (runs_.empty()) return true;
  std::size_t m = 0;
  for (const auto& [b, e] : runs_) m += e - b;
  nfx_.resize(m), nfy_.resize(m), nfz_.resize(m), nfq_.resize(m), nfg_.resize(m);
  {
    // Plain indexed loops, one array at a time: they vectorise.
    std::size_t at = 0;
    for (const auto& [b, e] : runs_) {
      const std::size_t len = e - b;
      float *x = nfx_.data() + at, *y = nfy_.data() + at, *z = nfz_.data() + at,
            *q = nfq_.data() + at;
      const double *px = sx_.data() + b, *py = sy_.data() + b, *pz = sz_.data() + b,
                   *pq = sq_.data() + b;
      for (std::size_t i = 0; i < len; ++i) x[i] = float(px[i] - c.x);
      for (std::size_t i = 0; i < len; ++i) y[i] = float(py[i] - c.y);
      for (std::size_t i = 0; i < len; ++i) z[i] = float(pz[i] - c.z);
      for (std::size_t i = 0; i < len; ++i) q[i] = float(pq[i]);
      std::copy(sgi_.begin() + b, sgi_.begin() + e, nfg_.begin() + std::ptrdiff_t(at));
      at += len;
    }
  }
  gfx_.assign(m, 0.0f), gfy_.assign(m, 0.0f), gfz_.assign(m, 0.0f);
  direct_accumulate_mutual_single(
      targets, tfq_.data(), {nfx_.data(), nfy_.data(), nfz_.data(), nfq_.data(), nfg_.data(), m},
      gfx_.data(), gfy_.data(), gfz_.data(), e2);
  std::size_t at = 0;
  for (const auto& [b, e] : runs_)
    for (std::uint32_t t = b; t < e; ++t, ++at)
      fx_[t] += double(gfx_[at]), fy_[t] += double(gfy_[at]), fz_[t] += double(gfz_[at]);
  p2p_ += std::uint64_t(n) * m;
  single_pairs_ += std::uint64_t(n) * m;
  return true;
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
  const double t0 = seconds_now();
  // Near pairs of distinct cells each once, both ways (half the kernel's
  // work), where the CPU has the kernel for it.
  const bool mutual =
      mutual_near_ && direct_accumulate_mutual({}, nullptr, {}, nullptr, nullptr, nullptr, 0);
  const double theta2 = theta_ * theta_;
  auto accept = [&](const Node& A, const Node& B) {
    const Vec3 gap = A.centre - B.centre;
    const double reach = A.radius + B.radius, g2 = dot(gap, gap);
    return reach * reach < theta2 * g2;
  };
  const std::uint64_t direct_pairs = std::uint64_t(leaf_size_) * leaf_size_;
  // The previous lists stand while the cells are the same ones (a reused
  // build): pairs summed directly or split stay exact whatever the cells'
  // new radii, and a listed translation that no longer meets the criterion
  // is walked again from that pair (split until it does, or summed directly).
  lists_reused_ = reused_ && lists_valid_ && lists_theta_ == theta_ && lists_mutual_ == mutual;
  stack_.clear();
  if (lists_reused_) {
    std::size_t kept = 0;
    for (const auto& pr : m2l_pairs_) {
      const Node& A = nodes_[std::size_t(pr.first)];
      const Node& B = nodes_[std::size_t(pr.second)];
      if (accept(A, B))
        m2l_pairs_[kept++] = pr;
      else
        stack_.push_back(pr);
    }
    m2l_pairs_.resize(kept);
  } else {
    near_pairs_.clear();
    m2l_pairs_.clear();
    stack_.emplace_back(0, 0);
    lists_valid_ = true, lists_theta_ = theta_, lists_mutual_ = mutual;
  }
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
    if (accept(A, B)) {
      m2l_pairs_.emplace_back(a, b);
    } else if ((A.children == 0 && B.children == 0) ||
               std::uint64_t(A.end - A.begin) * (B.end - B.begin) <= direct_pairs) {
      // Two leaves, or two cells so small that their pairs cost less than
      // splitting them into many small translations: summed directly.
      if (mutual) {
        near_pairs_.emplace_back(std::min(a, b), std::max(a, b));  // summed both ways at once
      } else {
        near_pairs_.emplace_back(a, b);
        near_pairs_.emplace_back(b, a);
      }
    } else if (B.children == 0 || (A.children != 0 && A.radius >= B.radius)) {
      for (std::int32_t i = A.first_child; i < A.first_child + A.children; ++i)
        stack_.emplace_back(i, b);
    } else {
      for (std::int32_t j = B.first_child; j < B.first_child + B.children; ++j)
        stack_.emplace_back(a, j);
    }
  }

  const double t1 = seconds_now();
  // The translations, in the walk's order (a fixed order, so fixed bits),
  // each at its pair's order (FmmOptions::pair_orders): the lowest q whose
  // limit rho^2 <= theta^(2 (p-1) / (q-1)) the pair meets. The orders' terms are
  // numbered by total degree, so order q's are the first of order_'s: its
  // translation reads and writes the same arrays, fewer terms.
  for (auto& list : by_order_) list.clear();
  if (pair_orders_) {
    for (const auto& pr : m2l_pairs_) {
      const Node& A = nodes_[std::size_t(pr.first)];
      const Node& B = nodes_[std::size_t(pr.second)];
      const Vec3 gap = A.centre - B.centre;
      const double reach = A.radius + B.radius, rho2 = reach * reach / dot(gap, gap);
      int q = 1;
      while (q < order_ && !(rho2 <= order_limit2_[std::size_t(q)])) ++q;
      by_order_[std::size_t(q)].push_back(pr);
    }
  }
  if (options_vector_m2l_ != 0) {
    centres_.resize(nodes_.size());
    for (std::size_t k = 0; k < nodes_.size(); ++k) centres_[k] = nodes_[k].centre;
    zero_.assign(nt, 0.0), sink_.assign(nt, 0.0);
  }
  const int width = options_vector_m2l_ == int(FmmOptions::M2l::Batched) ? 1
                    : options_vector_m2l_ == int(FmmOptions::M2l::Simd4) ? 4
                                                                         : 8;
  for (int q = 1; q <= order_; ++q) {
    // Off: the walk's list as it is, at the full order.
    const auto& list = pair_orders_  ? by_order_[std::size_t(q)]
                       : q == order_ ? m2l_pairs_
                                     : by_order_[0];
    if (list.empty()) continue;
    if (options_vector_m2l_ == 0) {
      for (const auto& [a, b] : list) m2l(a, b, q);  // the reference, one pair at a time
    } else {
      m2l_runner(q, width)({list.data(), list.size(), centres_.data(), mult_.data(), mneg_.data(),
                            local_.data(), zero_.data(), sink_.data(), nt, eps2_});
      m2l_ += list.size();
    }
    m2l_by_order_[std::size_t(q)] += list.size();
  }
  const double t2 = seconds_now();

  // The near field, leaf by leaf: each target leaf's near leaves in memory
  // order (a fixed order, so fixed bits). A counting sort by target, then each
  // short list sorted: the pairs are many, the lists short.
  near_start_.assign(nodes_.size() + 1, 0);
  for (const auto& pr : near_pairs_) ++near_start_[std::size_t(pr.first) + 1];
  for (std::size_t k = 0; k < nodes_.size(); ++k) near_start_[k + 1] += near_start_[k];
  near_list_.resize(near_pairs_.size());
  {
    std::vector<std::int32_t>& fill = near_order_fill_;
    fill.assign(near_start_.begin(), near_start_.end() - 1);
    for (const auto& pr : near_pairs_)
      near_list_[std::size_t(fill[std::size_t(pr.first)]++)] = pr.second;
  }
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const auto first = near_list_.begin() + near_start_[k],
               last = near_list_.begin() + near_start_[k + 1];
    if (first == last) continue;
    std::sort(first, last);
    const std::span<const std::int32_t> list(&*first, std::size_t(last - first));
    if (mutual)
      near_field_mutual(std::int32_t(k), list);
    else
      near_field(nodes_[k], list);
  }
  const double t3 = seconds_now();

  // The translations summed U[m] = m! L[m].
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    for (std::size_t m = 0; m < nt; ++m) local_[k * nt + m] *= inv_fact_[m];
  // Down: each cell's local expansion moved to its children's centres (L2L),
  // parents first (a parent's index is below its children's).
  std::vector<double> pw(nt);
  auto powers = [&](Vec3 v, double* out) { scaled_powers(v, out); };
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
  // At the leaves' sources: F = -grad phi, phi(c + y) = sum_m L_m y^m
  // (l2p_leaf, unrolled for the order).
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const Node& node = nodes_[k];
    if (node.children != 0) continue;
    l2p_leaf(order_, local_.data() + k * nt, sx_.data(), sy_.data(), sz_.data(), node.begin,
             node.end, node.centre, fx_.data(), fy_.data(), fz_.data());
  }
  profile_.walk += t1 - t0;
  profile_.m2l += t2 - t1;
  profile_.near += t3 - t2;
  profile_.downward += seconds_now() - t3;
  for (std::size_t t = 0; t < n; ++t) out[order_of_[t]] = {fx_[t], fy_[t], fz_[t]};
}

}  // namespace alloy::multipole
