// A fast multipole method (FMM) for the same sums as multipole_tree.hpp,
//
//   F(x_i) = sum_j q_j K(x_i - p_j),   K(r) = r / (|r|^2 + eps^2)^(3/2) = -grad (1/s),
//
// at every source, each leaving out its own group (a magnet's own poles).
//
// Why (issue 16): the Barnes-Hut walk expands every far cell at every target,
// so its cost per target grows with log N times the cells' count, and 10,000
// magnets took 60 ms. Here far cells act on far cells: each cell's multipole
// expansion (order p, Cartesian, about its |q|-weighted centroid) is turned
// into a local expansion about the other cell's centre (M2L), once per pair of
// well-separated cells, and both cells get it (the derivative tensor is
// shared). Local expansions are passed down the tree (L2L) and evaluated once
// at each source (L2P). Pairs of cells that are not separated are split, the
// larger first, until both are leaves, whose sources are summed directly on
// the SIMD kernel (direct_kernel.hpp). This is the dual-tree walk of Dehnen's
// falcON (J. Comput. Phys. 179, 2002) with Cartesian Taylor expansions; the
// code is alloy's own.
//
// Groups are never split: the tree is built over atoms (a group's sources, or
// one ungrouped source) placed by their mean position, and a cell's radius
// covers all the sources of its atoms. Two separated cells therefore share no
// group, and a target's own group only ever meets it in the direct near field,
// which leaves it out exactly.
//
// The criterion: cells A and B (radii b_A, b_B about centres c_A, c_B) are
// separated when b_A + b_B < theta |c_A - c_B|. The error of order p falls as
// theta^p for neutral cells (magnets: dipole-led) and theta^(p+1) for masses;
// docs/magnetism.md "Fast summation" gives the measured error against (theta, p).
//
// The kernel's derivatives of any order come from the recurrence for radial
// functions of |r|^2, so the softened kernel is expanded exactly as the plain
// one. The tree and every sum are built by one thread in a fixed order: the
// same input gives bit-identical output.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "resolvers/common/multipole_tree.hpp"

namespace alloy::multipole {

struct FmmOptions {
  /// Separation parameter, in (0, 1): smaller is more accurate and slower.
  double theta = 0.5;
  /// Expansion order p, 1 to kMaxFmmOrder: the error falls as theta^p.
  int order = 4;
  /// Largest number of sources in a leaf (a leaf holds whole atoms, so a
  /// group larger than this is a leaf of its own).
  std::uint32_t leaf_size = 32;
  /// How the cell-to-cell translations run: one at a time (the reference),
  /// in batches of one lane, in batches of the widest SIMD the CPU has (eight
  /// lanes with AVX-512, four with AVX2 and FMA, else one), or of four lanes
  /// at most (Simd4, session 16's batches, for the bench's comparison). The
  /// bits differ between the first and the others by rounding only
  /// (tests/resolvers/magnetism/fmm_test.cpp).
  enum class M2l : std::uint8_t { Reference, Batched, Simd, Simd4 };
  M2l m2l = M2l::Simd;
  /// The near field between two distinct cells summed each pair once, both
  /// ways (direct_accumulate_mutual), where the CPU has that kernel; false:
  /// each way on its own (twice the kernel's work; the same sums to rounding).
  bool mutual_near = true;
  /// The near field in single precision (direct_kernel.hpp's float kernels,
  /// sixteen lanes, about twice as fast), where the CPU has the once-each
  /// kernel and a leaf's near region spans at most kSingleNearReach
  /// softening lengths: each pair's relative error is then below ~1e-4 and
  /// the sums' about 1e-6, far under the expansions' (issue 16's 1e-3). Off:
  /// double precision everywhere (no softening: always double).
  bool single_near = false;
  /// Keep the cells and the walk's lists of the previous build when the
  /// sources are the same ones (count, groups, which are zero) and the
  /// options the same: build() then only refreshes the positions, centres,
  /// radii and moments, and evaluate skips the walk while every listed
  /// translation still meets the criterion with the new radii (else it walks
  /// afresh). No cell may have grown past 1.5 times its radius at the last
  /// full build (else a full build). The bound holds either way; only the
  /// cells' shapes age, and the result depends on the history of builds, not
  /// only on the sources: off unless asked for (issue 16: "reuse of the tree
  /// between steps when bodies move little").
  bool reuse = false;
  /// Each separated pair translated at the lowest order q <= `order` whose
  /// error estimate for that pair stays within the one the full order is
  /// allowed at the separation limit. A neutral cell's field (magnets) is
  /// led by its dipole, the expansion's terms of total degree 2; at order q
  /// the terms left out are about rho^(q-1) of it, rho = (b_A + b_B) / |r|
  /// the pair's ratio (below theta). So q is the least with rho^(q-1) <=
  /// theta^(p-1), and at least 2 (order 1 leaves a dipole's field out
  /// altogether). For masses (led by the monopole, error rho^q) the rule is
  /// stricter than needed. Well-separated pairs are then cheaper (order 4
  /// costs 0.45 of order 5's contraction, order 3 0.18). Off: every pair at
  /// `order`.
  bool pair_orders = false;
};

/// FmmOptions::single_near applies to a leaf whose near cells (itself
/// included) lie within this many softening lengths of its centre: float's
/// 6e-8 rounding of coordinates of that size is then under 1e-4 of the
/// separation of two sources one softening length apart.
inline constexpr double kSingleNearReach = 1000;

inline constexpr int kMaxFmmOrder = 6;

/// Where an FMM's time goes, CPU seconds of the calling thread summed over the calls so far
/// (bench/scaling.cpp prints it; issue 16 asked for the profile by phase).
struct FmmProfile {
  double tree = 0;      ///< build(): atoms, the octree and the sources in tree order
  double upward = 0;    ///< build(): centres, radii and multipoles (P2M, M2M)
  double walk = 0;      ///< evaluate: the dual-tree walk that lists the cell pairs
  double m2l = 0;       ///< evaluate: the listed translations (M2L)
  double near = 0;      ///< evaluate: the direct near field (P2P, SIMD kernel)
  double downward = 0;  ///< evaluate: L2L and the local expansions at the sources (L2P)
  double total() const { return tree + upward + walk + m2l + near + downward; }
};

class Fmm {
 public:
  /// Builds the tree and the cells' multipole expansions over `sources`.
  void build(std::span<const Source> sources, double softening, FmmOptions options = {});
  /// out[i] for sources[i] as given to build(): the sum over every source not
  /// in its group (and not at its very position).
  void evaluate_at_sources(std::span<Vec3> out);

  std::size_t size() const { return src_.size(); }
  std::size_t cells() const { return nodes_.size(); }
  /// Cell-cell translations (each counted once though both cells get it) and
  /// source pairs summed directly, by the evaluations so far.
  std::uint64_t cell_interactions() const { return m2l_; }
  /// Of the translations, how many ran at each order 1..kMaxFmmOrder (index
  /// 0 unused), by the evaluations so far (FmmOptions::pair_orders).
  const std::array<std::uint64_t, kMaxFmmOrder + 1>& translations_by_order() const {
    return m2l_by_order_;
  }
  std::uint64_t direct_interactions() const { return p2p_; }
  /// Of those, the ones summed in single precision (FmmOptions::single_near).
  std::uint64_t single_interactions() const { return single_pairs_; }
  /// Whether the last build() kept the previous cells (FmmOptions::reuse),
  /// and whether the last evaluation kept the previous walk's lists.
  bool reused() const { return reused_; }
  bool lists_reused() const { return lists_reused_; }
  /// Time by phase over the calls so far.
  const FmmProfile& profile() const { return profile_; }

 private:
  struct Node {
    Vec3 centre;                       ///< expansion centre (|q|-weighted centroid of its sources)
    double radius = 0;                 ///< every source of the cell is within this of centre
    std::uint32_t begin = 0, end = 0;  ///< sources, in tree order
    std::int32_t first_child = -1;     ///< children are consecutive nodes
    std::int32_t children = 0;
    std::int32_t parent = -1;
    bool empty = true;  ///< every strength is zero
  };
  struct Atom {
    Vec3 centre;
    std::uint32_t first = 0, count = 0;  ///< into atom_members_
  };
  void make_tables(int order);
  std::int32_t make_node(Vec3 box_centre, double half, std::uint32_t begin, std::uint32_t end,
                         int depth, std::int32_t index);
  void upward();
  void scaled_powers(Vec3 s, double* out) const;
  void m2l(std::int32_t a, std::int32_t b, int order);
  void contract(int order, const double* mn, const double* d, double* u) const;
  void near_field(const Node& leaf, std::span<const std::int32_t> near);
  void near_field_mutual(std::int32_t k, std::span<const std::int32_t> near);
  bool near_field_single(std::int32_t k, std::span<const std::int32_t> near);
  bool try_reuse(std::span<const Source> sources);
  void integer_groups();

  double eps2_ = 0, theta_ = 0.5;
  int order_ = 0;
  std::uint32_t leaf_size_ = 32;
  // Multi-index tables for order_: the terms (a, b, c) with a + b + c <= p in
  // order of total degree; nterms_ of them.
  int nterms_ = 0;
  std::vector<std::uint8_t> ia_, ib_, ic_, deg_;
  std::vector<double> inv_fact_;            ///< 1 / (a! b! c!)
  std::vector<std::int32_t> index_;         ///< (a, b, c) -> term, (p+1)^3 entries
  std::vector<std::int32_t> dx_, dy_, dz_;  ///< term minus one x, y, z (-1: none)
  // The derivative recurrence: for term t, the axis it was reached by, the
  // term one and two steps back along it, and the factor of the second.
  std::vector<std::int8_t> rec_axis_;
  std::vector<std::int32_t> rec_prev_, rec_prev2_;
  std::vector<double> rec_k_;
  std::vector<double> rcp_;           ///< 1 / (the term's exponent along rec_axis_)
  std::vector<std::int32_t> offset_;  ///< term -> (a (p+1) + b) (p+1) + c
  std::vector<std::int32_t> prefix_;  ///< degree n -> number of terms of degree <= n
  // M2M / L2L: binomial shifts.
  struct ShiftTerm {
    std::int32_t to, from, power;
  };
  std::vector<ShiftTerm> m2m_terms_;  ///< M_p[to] += M_c[from] s^power / power!
  std::vector<ShiftTerm> l2l_terms_;  ///< L_c[to] += L_p[from] C(from, to) t^power
  std::vector<double> l2l_coef_;

  std::vector<Source> src_;              ///< in tree order
  std::vector<std::uint32_t> order_of_;  ///< tree position -> index given to build()
  std::vector<Atom> atoms_;
  std::vector<std::uint32_t> atom_members_, atom_order_, scratch_;
  std::vector<Node> nodes_;
  std::vector<double> mult_, local_;  ///< nterms_ per node
  std::vector<double> mneg_;          ///< (-1)^|k| M[k], per node
  std::vector<double> sx_, sy_, sz_, sq_, sg_, tg_, fx_, fy_, fz_;
  std::vector<std::int32_t> leaf_of_;
  std::vector<std::pair<std::int32_t, std::int32_t>> stack_;
  std::vector<std::pair<std::int32_t, std::int32_t>> near_pairs_;  ///< (target leaf, source leaf)
  std::vector<std::pair<std::int32_t, std::int32_t>> m2l_pairs_;   ///< separated cells, both ways
  std::vector<std::int32_t> near_start_, near_list_;  ///< near sources by target, counting-sorted
  std::vector<std::int32_t> near_order_fill_;
  int options_vector_m2l_ = 2;
  bool mutual_near_ = true;
  bool single_near_ = false;
  std::vector<std::int32_t> sgi_, tgi_;       ///< groups as integers (-1 / -2: none), single_near
  std::vector<float> tfx_, tfy_, tfz_, tfq_;  ///< one leaf's targets, single
  std::vector<float> nfx_, nfy_, nfz_, nfq_;  ///< its near sources, single
  std::vector<std::int32_t> nfg_;             ///< their groups
  std::vector<float> gfx_, gfy_, gfz_;        ///< their mutual sums, single
  std::uint64_t single_pairs_ = 0;
  // Reuse (FmmOptions::reuse): the settings of the last full build, each
  // cell's radius then, and the settings the walk's lists were made with.
  bool reused_ = false, lists_reused_ = false, lists_valid_ = false, lists_mutual_ = false;
  std::uint32_t built_leaf_ = 0;
  double built_eps2_ = -1, lists_theta_ = 0, built_root_radius_ = 0;
  std::vector<double> built_radius_;
  std::vector<char> built_empty_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> runs_;  ///< gathered source ranges
  std::vector<double> gx_, gy_, gz_;                           ///< their mutual sums
  std::vector<Vec3> centres_;                   ///< node centres, for the batched M2L
  std::vector<double> zero_, sink_;             ///< the batches' padding
  std::vector<double> nx_, ny_, nz_, nq_, ng_;  ///< one leaf's near sources, gathered
  std::uint64_t m2l_ = 0, p2p_ = 0;
  // FmmOptions::pair_orders: (rho^2 limit) per order q < order_ (rho^q <=
  // theta^order_), the walk's translations sorted by the order they run at
  // (stable: the list's order within each), and the counts.
  bool pair_orders_ = false;
  std::array<double, kMaxFmmOrder + 1> order_limit2_{};
  std::array<std::vector<std::pair<std::int32_t, std::int32_t>>, kMaxFmmOrder + 1> by_order_;
  std::array<std::uint64_t, kMaxFmmOrder + 1> m2l_by_order_{};
  FmmProfile profile_;
};

}  // namespace alloy::multipole
