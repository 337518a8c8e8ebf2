// Interaction rigid_body <- gravity: the force m * g on every body that has a
// gravitational acceleration (the `gravity` column, written by whichever
// gravity resolver acts where the body is) and a mass, queued every step.
#pragma once

#include "resolvers/rigid_body/engine.hpp"
#include "runtime/world.hpp"

namespace alloy::rigid {

class RigidBodyFromGravity final : public Interaction {
 public:
  explicit RigidBodyFromGravity(RigidBodyEngine& target) : target_(target) {}
  void apply(const WorldView& world) override;

 private:
  RigidBodyEngine& target_;
  PropertyId gravity_ = kNoProperty, mass_ = kNoProperty;
};

}  // namespace alloy::rigid
