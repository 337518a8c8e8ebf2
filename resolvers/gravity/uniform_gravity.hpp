// The `gravity.uniform` resolver: the same gravitational acceleration for every
// body that has mass (a planet's surface; paper section 3: "a constant
// downwards vector"). It is not ODE's gravity: it writes the `gravity` column,
// and rigid_body_from_gravity turns it into forces, so that another gravity
// model (N-body in orbit, an area of its own) can replace it without the rigid
// body knowing.
//
// Reads   mass, density, static.   Writes  gravity (m/s^2).
// Provides "gravity": one provider per scope; in an area of its own it acts on
//         the area's objects only, and an object that leaves the area loses
//         the value (on_scope_exit), so no stale g pushes it elsewhere.
// Cost    nothing per step unless `static` was edited: the column is written in
//         build() (after any structural change) and stays valid.
#pragma once

#include <vector>

#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::gravity {

/// The property this resolver writes.
PropertyDef gravity_property();

class UniformGravity final : public Resolver {
 public:
  /// `g`: gravitational acceleration, m/s^2 (the 2D kit has y up: {0, -9.81, 0}).
  explicit UniformGravity(Vec3 g) : g_(g) {}
  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  void on_scope_exit(ResolverAccess& access, std::span<const std::uint32_t> left) override;
  Vec3 g() const { return g_; }
  /// Potential energy -m g . x of the bodies it acts on (store), and its
  /// change since the last report (transfer "gravity": what the rigid body
  /// books as gravity's work on them). docs/energy.md.
  void report_energy(const WorldView& view, EnergyReport& out) override;

 private:
  void write(ResolverAccess& access);

  Vec3 g_;
  PropertyId mass_ = kNoProperty, density_ = kNoProperty, static_ = kNoProperty,
             gravity_ = kNoProperty;
  std::uint64_t static_seen_ = ~std::uint64_t(0);
  double reported_potential_ = 0;  // J, at the last report
  bool reported_ = false;
};

}  // namespace alloy::gravity
