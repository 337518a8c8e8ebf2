// A Barnes-Hut octree for sums of the Plummer-softened inverse-square kernel
//
//   F(x) = sum_j q_j K(x - p_j),   K(r) = r / (|r|^2 + eps^2)^(3/2)
//
// over point sources of signed strength q_j (magnetic poles: A*m; masses: kg).
// Each cell carries its monopole, dipole, quadrupole and octupole moments about
// its expansion centre c (the |q|-weighted centroid of its sources); a cell
// whose sources all lie within b_max of c is used whole, through the Taylor
// expansion of the softened kernel to third order, when
//
//   b_max < theta * |x - c|        (the opening criterion)
//
// and opened otherwise; leaves (at most leaf_size sources) are summed directly.
// When the targets are a group's sources (a magnet's two poles), the criterion
// holds for the group's bounding sphere, b_max < theta * (|x_g - c| - r_g), and
// a cell is taken whole or opened for all of them together.
// The expansion goes to the octupole because magnets are neutral: a cell of
// whole magnets has Q ~ 0 and its leading term is the dipole, so the error of
// an expansion to order p is (b/r)^p relative to the cell's field, not
// (b/r)^(p+1) as for masses; p = 3 gives theta^3 where gravity's usual
// monopole + quadrupole gives theta^3 too (docs/magnetism.md, "Summation").
// Sources are grouped (a magnet's two poles): a target excludes one group, as
// a part never acts on itself.
// At the sources themselves (evaluate_at_sources) the targets go in blocks of
// whole groups that share one walk; each block's near field is one SIMD direct
// sum (direct_kernel.hpp) and its far cells are expanded at all its targets in
// one vectorised loop (issue 16; docs/performance.md "Magnetic forces"). The tree is plain data
// built by one thread in a fixed order, so the same input gives bit-identical output.
//
// Shared by magnetism (magnetic_forces) and gravity.nbody; no world, no
// properties. docs/magnetism.md argues the choice and gives the measured error.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "runtime/math.hpp"

namespace alloy::multipole {

inline constexpr std::uint32_t kNoGroup = 0xffffffffu;
class Fmm;

struct Source {
  Vec3 position;
  double strength = 0;
  std::uint32_t group = kNoGroup;  ///< sources of one group do not act on a target of it
};

struct TreeOptions {
  /// Opening angle, in (0, 1): smaller is more accurate and slower.
  double theta = 0.5;
  /// Largest number of sources in a leaf. 64: the near field runs on the SIMD
  /// kernel, so large leaves (fewer, nearer cells) are cheaper than deep trees
  /// (bench/scaling.cpp --magnets; docs/performance.md).
  std::uint32_t leaf_size = 64;
  /// evaluate_at_sources: targets (whole groups, neighbours in tree order)
  /// that share one walk of the tree and one interaction list; a group larger
  /// than this is a block of its own.
  std::uint32_t block = 32;
  /// build() keeps the cells of the previous build and only recomputes their
  /// moments and radii (a refit) when the sources are the same ones (count,
  /// groups, signs) and no cell's radius grew past 1.5 times its radius at
  /// the last full build. The radii are always current, so the opening
  /// criterion, and the error it bounds, hold either way; only the cells'
  /// shapes age. The result then depends on the history of the tree, not
  /// only on the sources: off unless asked for.
  bool reuse = false;
  /// 0: the Barnes-Hut walk above. From 1: build() builds the fast multipole
  /// method of fmm.hpp instead, with expansions of this order, `theta` as its
  /// separation parameter and `leaf_size` as its leaves' size, and
  /// evaluate_at_sources() runs it (reuse then keeps the FMM's cells and
  /// lists, FmmOptions::reuse; evaluate() sums
  /// directly, exactly).
  int fmm_order = 0;
  /// With fmm_order: the FMM's near field in single precision where the
  /// softening allows it (FmmOptions::single_near; about twice as fast, its
  /// error far under the expansions'). Off: double, as before.
  bool fmm_single_near = false;
  /// With fmm_order: each translation at the lowest order its pair's
  /// separation allows (FmmOptions::pair_orders). Off: all at fmm_order.
  bool fmm_pair_orders = false;
};

/// The softened kernel K(r), 1/m^2 along r; zero at r = 0 when eps = 0.
inline Vec3 kernel(Vec3 r, double eps2) {
  const double s2 = dot(r, r) + eps2;
  if (s2 <= 0) return {};
  return r * (1.0 / (s2 * std::sqrt(s2)));
}

/// Direct O(N) sum at one point: every source not in `exclude` and not at x itself.
Vec3 direct_sum(std::span<const Source> sources, double softening, Vec3 x,
                std::uint32_t exclude = kNoGroup);

/// The same at every source (its own group left out), all pairs, with the
/// SIMD kernel of direct_kernel.hpp: out[i] for sources[i]. O(N^2), exact to
/// rounding; a source at another's very position contributes nothing.
void direct_at_sources(std::span<const Source> sources, double softening, std::span<Vec3> out);

class Tree {
 public:
  Tree();
  ~Tree();
  Tree(Tree&&) noexcept;
  Tree& operator=(Tree&&) noexcept;
  /// Builds the tree over `sources` (copied); with options.reuse, refits the
  /// previous one when it can (see TreeOptions::reuse).
  void build(std::span<const Source> sources, double softening, TreeOptions options = {});
  /// Whether the last build() was a refit of the cells before it.
  bool refitted() const { return refitted_; }

  /// sum_j q_j K(x - p_j) over sources not in group `exclude` and not at x itself.
  Vec3 evaluate(Vec3 x, std::uint32_t exclude = kNoGroup) const;

  /// The same at every source, excluding its own group: out[i] for sources[i]
  /// as given to build(). Targets go in blocks of whole groups, neighbours in
  /// tree order: one walk per block collects the cells far enough from the
  /// block's bounding sphere to be used whole and the leaves that are not,
  /// then every target sums the cells' expansions and, with the SIMD kernel
  /// of direct_kernel.hpp, the leaves' sources.
  void evaluate_at_sources(std::span<Vec3> out) const;
  /// The previous method (before issue 16), for the bench's comparison: one
  /// walk per group, cells and pairs one target at a time, no SIMD.
  void evaluate_at_sources_per_group(std::span<Vec3> out) const;

  std::size_t size() const { return sources_.size(); }
  std::size_t cells() const { return nodes_.size(); }
  /// Cells used whole and source pairs summed directly by the evaluations so
  /// far (what the cost is made of).
  std::uint64_t cell_interactions() const { return cell_interactions_; }
  std::uint64_t direct_interactions() const { return direct_interactions_; }

 private:
  struct Node {
    Vec3 box_centre;
    double half = 0;   ///< half side of the cube
    Vec3 centre;       ///< expansion centre
    double b2 = 0;     ///< b_max^2: every source is within b_max of centre
    double reach = 0;  ///< b_max / theta: used whole from farther than this
    double q = 0;      ///< monopole
    Vec3 d;            ///< dipole about centre
    double m[6] = {};  ///< quadrupole about centre: xx yy zz xy xz yz
    /// octupole about centre: xxx yyy zzz xxy xxz xyy yyz xzz yzz xyz
    double o[10] = {};
    std::uint32_t begin = 0, end = 0;
    std::int32_t child[8];
    bool leaf = true;
    bool empty = true;  ///< every strength is zero
  };
  bool try_refit(std::span<const Source> sources);
  void finish_build();
  std::int32_t make_node(Vec3 box_centre, double half, std::uint32_t begin, std::uint32_t end,
                         int depth);
  void moments(Node& n) const;
  Vec3 cell_field(const Node& n, Vec3 x) const;
  static void add_cell_field(const Node& n, const double* x, const double* y, const double* z,
                             std::size_t m, double eps2, double* fx, double* fy, double* fz);
  /// Sums at the targets `x` (the members of group `exclude`, or one point),
  /// skipping that group and the source at tree position `self`.
  void walk(std::span<const Vec3> x, std::uint32_t exclude, std::uint32_t self,
            std::span<Vec3> out) const;

  double eps2_ = 0, theta2_ = 0.25;
  std::uint32_t leaf_size_ = 8;
  std::vector<Source> sources_;       ///< in tree order
  std::vector<std::uint32_t> order_;  ///< tree position -> index given to build()
  std::vector<std::uint32_t> group_start_, group_members_;  ///< CSR: group -> tree positions
  std::vector<Node> nodes_;
  std::vector<double> built_b2_;  ///< each cell's b_max^2 at the last full build
  /// The sources in tree order as arrays, for the SIMD near field; groups as
  /// doubles (-1: none).
  std::vector<double> sx_, sy_, sz_, sq_, sg_;
  std::uint32_t block_ = 32;
  bool refitted_ = false;
  /// Set when the last build() was an FMM one (TreeOptions::fmm_order).
  std::unique_ptr<Fmm> fmm_;
  bool use_fmm_ = false;
  std::vector<std::uint32_t> scratch_;
  mutable std::vector<std::int32_t> stack_;
  mutable std::uint64_t cell_interactions_ = 0, direct_interactions_ = 0;
};

}  // namespace alloy::multipole
