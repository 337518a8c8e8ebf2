// Interaction rigid_body <- collisions (paper 3.4: "an interaction is required
// to feed back the contact forces calculated by the collisions derived
// property set into the rigid body resolver"). Every touching pair becomes a
// contact command with the pair's combined surface; the rigid body makes ODE
// contact joints of them in its next advance.
#pragma once

#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"

namespace alloy::rigid {

class RigidBodyFromCollisions final : public Interaction {
 public:
  /// `bounce_velocity`: approach speeds below it do not bounce (m/s). At 240 Hz
  /// gravity alone adds 0.04 m/s per step to a resting part; 0.1 m/s keeps
  /// resting contacts from hopping while a striker at walking pace still bounces.
  RigidBodyFromCollisions(RigidBodyResolver& target, const CollisionSet& contacts, double bounce_velocity);
  void apply(const WorldView& world) override;

  /// Friction of a pair: sqrt(mu_a * mu_b) (Box2D's rule): lies between the
  /// two, and a frictionless part (mu = 0) slides on anything.
  static double mix_friction(double a, double b);
  /// Restitution of a pair: the larger (Box2D's rule): a rubber ball bounces
  /// on a dead floor.
  static double mix_restitution(double a, double b);

  static constexpr double kDefaultFriction = 0.5;
  static constexpr double kDefaultRestitution = 0.0;

 private:
  RigidBodyResolver& target_;
  const CollisionSet& contacts_;
  double bounce_velocity_;
  PropertyId friction_ = kNoProperty, restitution_ = kNoProperty;
  std::vector<ContactCommand> commands_;  // the step's, handed over at once
};

}  // namespace alloy::rigid
