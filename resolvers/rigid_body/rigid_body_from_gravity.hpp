// Interaction rigid_body <- gravity: the force m * g on every body that has a
// gravitational acceleration (the `gravity` column, written by whichever
// gravity resolver acts where the body is) and a mass, queued every step.
#pragma once

#include "resolvers/rigid_body/rigid_body.hpp"

namespace alloy::rigid {

class RigidBodyFromGravity final : public Interaction {
 public:
  explicit RigidBodyFromGravity(RigidBodyResolver& target) : target_(target) {}
  void apply(const WorldView& world) override;

 private:
  RigidBodyResolver& target_;
  PropertyId gravity_ = kNoProperty, mass_ = kNoProperty;
};

}  // namespace alloy::rigid
