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
//          resolvers/common/fmm.hpp (O(n)). Both at settings chosen, as the
//          cheapest measured, to keep the RMS relative error of the
//          accelerations within kErrorBound on four layouts (a cold grid, a
//          Gaussian cluster, a uniform cube and a Plummer sphere) at every
//          size where each is used (tests: DISABLED_FmmSettingsSweep; the
//          bench: bench/scaling.cpp --gravity; docs/gravity.md "Many
//          bodies"). Nothing in a step in which no position, mass or
//          membership changed.
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

/// The bound the summation's settings below are chosen for: RMS relative
/// error of the accelerations against the direct sum, sqrt(sum |a - a_direct|^2
/// / sum |a_direct|^2), at most this on every layout measured (issue 16's
/// bound for the fast methods). The settings keep it with a margin (at most
/// 8.5e-4 measured), since the error moves with the layout.
inline constexpr double kErrorBound = 1e-3;
/// From this many sources the resolver sums with the tree. The walk (its
/// near field on the SIMD kernel) is faster than the scalar direct sum at
/// every size measured, 30 bodies up (2.2 times at 50, 3.3 at 100, 5.2 at
/// 300; session 17): the limit only keeps the direct sum's exact bits for
/// small systems such as the bundled space scene's handful of bodies (512
/// until session 16).
inline constexpr std::size_t kTreeFromMasses = 64;
/// The FMM's separation parameter for gravity: every mass is positive, so a
/// cell's monopole dominates and the error falls as theta^(p+1).
inline constexpr double kTreeTheta = 0.55;
/// 0: the Barnes-Hut walk; from 1, the FMM with expansions of that order
/// (theta then its separation parameter). 4, with theta 0.55 and leaves of
/// 48, by measurement (issue 16, session 17; DISABLED_FmmSettingsSweep over
/// orders 1 to 6, theta 0.4 to 0.8, leaves 16 to 64): the cheapest setting
/// with the error at most 7.9e-4 on every layout from 1,000 to 20,000
/// bodies; order 5 (session 16's) gave 2.6e-4 to 3.3e-4 for 1.3 times the
/// time at 10,000 (grid: 9.8 ms against 7.5 ms, same run).
inline constexpr int kTreeOrder = 4;
/// Largest number of bodies in a leaf (the FMM's balance of near field and
/// translations; the Barnes-Hut walk's own default is 64).
inline constexpr std::uint32_t kTreeLeaf = 48;
/// The resolver sums with the FMM (the settings above) from this many masses
/// and with the Barnes-Hut walk (kWalkTheta, kWalkLeaf) below: the walk was
/// 1.4 to 1.6 times faster at 300 to 1,000 bodies, the two within 7 % of
/// each other at 1,500 to 3,000, the FMM 0.8 of it at 5,000 (summed over the
/// four layouts; session 17, load 10).
inline constexpr std::size_t kFmmFromMasses = 2000;
/// The walk's opening angle and leaves: the cheapest setting with its error
/// at most 8.4e-4 on the four layouts from 300 to 3,000 bodies (theta 0.6
/// reaches 9.3e-4, 0.65 1.8e-3; 0.5, session 16's, 1.07 times the time).
inline constexpr double kWalkTheta = 0.55;
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
