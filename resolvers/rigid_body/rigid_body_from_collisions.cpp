#include "resolvers/rigid_body/rigid_body_from_collisions.hpp"

#include <algorithm>
#include <cmath>

namespace alloy::rigid {

RigidBodyFromCollisions::RigidBodyFromCollisions(RigidBodyResolver& target,
                                                 const CollisionSet& contacts,
                                                 double bounce_velocity)
    : target_(target), contacts_(contacts), bounce_velocity_(bounce_velocity) {}

double RigidBodyFromCollisions::mix_friction(double a, double b) {
  return std::sqrt(a * b);
}
double RigidBodyFromCollisions::mix_restitution(double a, double b) {
  return std::max(a, b);
}

void RigidBodyFromCollisions::apply(const WorldView& world) {
  if (friction_ == kNoProperty) {
    friction_ = world.property("friction");
    restitution_ = world.property("restitution");
  }
  const auto friction = world.column<double>(friction_);
  const auto restitution = world.column<double>(restitution_);
  // Every touching pair, in (a, b) order, its points referred to by their
  // place in the collision set's list (copied by the rigid body in one block).
  commands_.clear();
  for (const ContactPair& p : contacts_.touching()) {
    ContactCommand& c = commands_.emplace_back();
    c.a = p.a, c.b = p.b;
    c.first = p.first, c.count = p.count;
    c.friction = mix_friction(friction.value_or(p.a.index, kDefaultFriction),
                              friction.value_or(p.b.index, kDefaultFriction));
    c.restitution =
        std::clamp(mix_restitution(restitution.value_or(p.a.index, kDefaultRestitution),
                                   restitution.value_or(p.b.index, kDefaultRestitution)),
                   0.0, 1.0);
    c.bounce_velocity = bounce_velocity_;
  }
  // Parts that tunnelled go back to where they first touched (continuous detection).
  for (const Sweep& s : contacts_.sweeps()) target_.displace(s.part, s.displacement);
  // Parts buried in a heap wait, held still, until the heap has spread.
  target_.hold(contacts_.waiting());
  target_.add_contacts(commands_, contacts_.points());
}

}  // namespace alloy::rigid
