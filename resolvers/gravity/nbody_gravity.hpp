// The `gravity.nbody` resolver: Newtonian gravity between every pair of masses
// in its scope (paper section 3: "in space we might substitute a more involved
// gravity model for orbiting bodies"). Like gravity.uniform it only writes the
// `gravity` column; rigid_body_from_gravity turns it into forces m * g, so the
// two models are interchangeable per area and can be swapped while running.
//
//   a_i = sum_{j != i} G m_j (r_j - r_i) / (|r_j - r_i|^2 + eps^2)^(3/2)
//
// Sources  every object with a mass, static ones included (a planet is an
//          immovable source): by default in the whole world, since an area
//          chooses how its bodies' gravity is computed, not which masses
//          exist (a probe on the planet's tower, in an area of its own, is
//          still pulled by the planet); with `sources = "area"`, only those in
//          the stage's own scope (an isolated system).
// Targets  the non-static objects with a mass in the stage's scope: they get
//          a `gravity` value.
// Reads    position, mass, density, static.   Writes  gravity (m/s^2).
// Order    it reads `position`, which the rigid body writes, so it runs after
//          the rigid body in each advance: the accelerations are those of the
//          positions just written, queued as forces by the interact phase and
//          applied in the next advance. With ODE's step (v += dt F/m, then
//          x += dt v) that is semi-implicit (symplectic) Euler, first order.
// Cost     below kTreeFromMasses sources, O(n^2) pairs by direct summation in
//          a fixed order (accelerations(): the bundled space scene's bits);
//          from there the Barnes-Hut walk of resolvers/common/multipole_tree
//          and from kFmmFromMasses the fast multipole method of
//          resolvers/common/fmm.hpp (its FMM mode; O(n)), RMS relative error of
//          the accelerations ~3e-4 on a cold grid and ~1e-4 on a Gaussian
//          cluster at kTreeTheta and kTreeOrder, measured by bench/scaling.cpp
//          --gravity). In session 15 the FMM took 1.3 to 2 times the
//          Barnes-Hut walk's time; its batched translations and once-each
//          near field (session 16) made it 0.84 to 0.93 of it at 10,000.
//          Nothing in a step in which no
//          position, mass or membership changed.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "resolvers/common/fmm.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::gravity {

/// The SI gravitational constant (CODATA 2018), m^3 / (kg s^2).
inline constexpr double kGravitationalConstant = 6.67430e-11;

/// Accelerations at the points `at` from the point masses (`source`, `mass`),
/// by direct summation: O(at.size() * source.size()). `softening` is eps, m.
/// A source at the point itself (or coincident, with eps = 0) exerts nothing.
/// out[i] is overwritten.
void accelerations(std::span<const Vec3> at, std::span<const Vec3> source,
                   std::span<const double> mass, double G, double softening, std::span<Vec3> out);

/// From this many sources the resolver sums with the tree (measured crossover
/// with the direct sum, bench/scaling.cpp --gravity; the space scene has a
/// handful of bodies and keeps the direct sum's bits).
inline constexpr std::size_t kTreeFromMasses = 512;
/// The summation's separation parameter for gravity: every mass is positive,
/// so a cell's monopole dominates and the error falls fast with the order.
inline constexpr double kTreeTheta = 0.55;
/// 0: the Barnes-Hut walk; from 1, the FMM with expansions of that order
/// (theta then its separation parameter). 5, with leaves of kTreeLeaf, by
/// measurement (issue 16, session 16; bench/scaling.cpp --gravity): at 10,000
/// bodies 0.84 (grid) and 0.93 (Gaussian cluster) of the Barnes-Hut walk's
/// time (theta 0.5), at about its error (2.6e-4 against 2.9e-4 on the grid,
/// 1.05e-4 against 9.9e-5 on the cluster).
inline constexpr int kTreeOrder = 5;
/// Largest number of bodies in a leaf (the FMM's balance of near field and
/// translations; the Barnes-Hut walk's own default is 64).
inline constexpr std::uint32_t kTreeLeaf = 48;
/// The resolver sums with the FMM (the settings above) from this many masses
/// and with the Barnes-Hut walk (kWalkTheta, kWalkLeaf) below: the walk was
/// 1.4 to 1.9 times faster at 300 to 1,000 bodies, the two even near 3,000,
/// the FMM 0.84 (grid) to 0.93 (cluster) of it at 10,000 (bench/scaling.cpp
/// --gravity, session 16, load 13).
inline constexpr std::size_t kFmmFromMasses = 4000;
inline constexpr double kWalkTheta = 0.5;
inline constexpr std::uint32_t kWalkLeaf = 64;

/// Accelerations at every source from all the others, with the Barnes-Hut
/// tree at opening angle `theta` (or, with `order` from 1, the FMM); `tree`
/// keeps its memory between calls. out[i] for source[i]; overwritten.
void tree_accelerations(std::span<const Vec3> source, std::span<const double> mass, double G,
                        double softening, multipole::Tree& tree, std::span<Vec3> out,
                        double theta = kTreeTheta, int order = kTreeOrder,
                        std::uint32_t leaf_size = kTreeLeaf);

class NBodyGravity final : public Resolver {
 public:
  /// `area_sources`: only masses in the stage's own scope attract (else every mass).
  NBodyGravity(double G, double softening, bool area_sources = false)
      : G_(G), softening_(softening), area_sources_(area_sources) {}
  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  /// Objects that left this resolver's area lose the value it wrote for them.
  void on_scope_exit(ResolverAccess& access, std::span<const std::uint32_t> left) override;

  double G() const { return G_; }
  double softening() const { return softening_; }
  /// How many times the accelerations were computed (tests: skipped when still).
  std::uint64_t evaluations() const { return evaluations_; }

 private:
  void resolve_ids(const WorldView& v);
  /// Position, mass, density and static counters (values and memberships) and the scope's version.
  using Counters = std::array<std::uint64_t, 8>;
  Counters counters(const WorldView& v) const;
  void compute(ResolverAccess& access);

  double G_, softening_;
  bool area_sources_;
  PropertyId position_ = kNoProperty, mass_ = kNoProperty, density_ = kNoProperty,
             static_ = kNoProperty, gravity_ = kNoProperty;
  Counters seen_{};  // counters() at the last evaluation
  bool evaluated_ = false;
  std::uint64_t evaluations_ = 0;
  // Scratch, kept to avoid allocating each step.
  std::vector<std::uint32_t> masses_, targets_;
  std::vector<Vec3> source_x_, target_x_, a_;
  std::vector<double> source_m_;
  std::vector<Vec3> source_a_;
  /// From kTreeFromMasses: the masses gathered once, as the summation takes
  /// them (no second copy per step).
  std::vector<multipole::Source> sources_;
  multipole::Tree tree_;  ///< the Barnes-Hut walk, below kFmmFromMasses
  multipole::Fmm fmm_;    ///< the FMM, held directly (not through a Tree, which copies the sources)
};

}  // namespace alloy::gravity
