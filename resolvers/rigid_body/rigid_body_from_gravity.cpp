#include "resolvers/rigid_body/rigid_body_from_gravity.hpp"

namespace alloy::rigid {

void RigidBodyFromGravity::apply(const WorldView& world) {
  if (gravity_ == kNoProperty) {
    gravity_ = world.property("gravity");
    mass_ = world.property("mass");
  }
  const auto gravity = world.column<Vec3>(gravity_);
  const auto mass = world.column<double>(mass_);
  for (std::uint32_t s : gravity.members()) {
    const Vec3 g = gravity[s];
    if (g == Vec3{} || !mass.has(s)) continue;
    target_.add_force(s, mass[s] * g);
  }
}

}  // namespace alloy::rigid
