#include "resolvers/gravity/uniform_gravity.hpp"

namespace alloy::gravity {

PropertyDef gravity_property() {
  return {.name = "gravity",
          .kind = PropertyKind::Vec3,
          .unit = "m/s^2",
          .doc = "gravitational acceleration at the body (written by a gravity resolver)"};
}

void UniformGravity::write(ResolverAccess& access) {
  if (gravity_ == kNoProperty) {
    mass_ = access.property("mass"), density_ = access.property("density");
    static_ = access.property("static"), gravity_ = access.property("gravity");
  }
  const auto mass = access.column<double>(mass_);
  const auto density = access.column<double>(density_);
  const auto is_static = access.column<std::uint8_t>(static_);
  auto gravity = access.writer<Vec3>(gravity_);
  // Objects that carried gravity and no longer qualify (made static) get none.
  for (std::uint32_t s : gravity.members())
    if (!(mass.has(s) || density.has(s)) || is_static.value_or(s, 0)) gravity.set(s, Vec3{});
  auto visit = [&](std::uint32_t s) {
    if (!is_static.value_or(s, 0)) gravity.set(s, g_);  // set() moves the version only on a change
  };
  // Both lists (an object may carry both; the second set() changes nothing).
  // Member lists are refreshed between phases, so a mass the rigid body just
  // wrote from density may be in neither list yet: the density list has it.
  for (std::uint32_t s : mass.members()) visit(s);
  for (std::uint32_t s : density.members()) visit(s);
  static_seen_ = is_static.version();
}

void UniformGravity::build(ResolverAccess& access) {
  write(access);
}

void UniformGravity::advance(ResolverAccess& access, double) {
  // Membership changes come through build(); only a value edit of `static`
  // (a part fixed or freed) changes who feels gravity between builds.
  if (access.store().column(static_).version() != static_seen_) write(access);
}

void UniformGravity::report_energy(const WorldView& view, EnergyReport& out) {
  // Over the bodies that feel this g (the gravity column in the stage's
  // scope): U = -m g . x. A body that joins or leaves moves U with no work
  // done; the books show that as a residue (docs/energy.md).
  const auto gravity = view.column<Vec3>("gravity");
  const auto mass = view.column<double>("mass");
  const auto position = view.column<Vec3>("position");
  double u = 0;
  for (std::uint32_t s : gravity.members())
    if (mass.has(s) && position.has(s)) u -= mass[s] * dot(gravity[s], position[s]);
  out.store("potential energy (uniform field)", u);
  // The energy the field gave the bodies is what its store lost.
  out.transfer("gravity", reported_ ? u - reported_potential_ : 0.0);
  reported_potential_ = u, reported_ = true;
}

void UniformGravity::on_scope_exit(ResolverAccess& access, std::span<const std::uint32_t> left) {
  if (gravity_ == kNoProperty) gravity_ = access.property("gravity");
  auto gravity = access.writer<Vec3>(gravity_);
  for (std::uint32_t s : left) gravity.erase(s);
}

}  // namespace alloy::gravity
