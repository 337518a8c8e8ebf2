#include "resolvers/rigid_body/rigid_body_from_gravity.hpp"

namespace alloy::rigid {

void RigidBodyFromGravity::apply(const WorldView& world) {
  if (gravity_ == kNoProperty) {
    gravity_ = world.property("gravity");
    mass_ = world.property("mass");
  }
  const auto gravity = world.column<Vec3>(gravity_);
  const auto mass = world.column<double>(mass_);
  // One g for every member, each with a mass (gravity.uniform's field): the
  // engine may take it as its world's gravity (add_uniform_gravity).
  const auto members = gravity.members();
  if (!members.empty()) {
    const Vec3 g0 = gravity[members[0]];
    bool uniform = true;
    for (std::uint32_t s : members)
      if (!(gravity[s] == g0) || !mass.has(s)) {
        uniform = false;
        break;
      }
    if (uniform && (g0 == Vec3{} || target_.add_uniform_gravity(g0, members))) return;
  }
  for (std::uint32_t s : members) {
    const Vec3 g = gravity[s];
    if (g == Vec3{} || !mass.has(s)) continue;
    target_.add_force(s, mass[s] * g);
  }
}

}  // namespace alloy::rigid
