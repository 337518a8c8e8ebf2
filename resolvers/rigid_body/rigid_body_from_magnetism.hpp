// The (Rigid body <- Magnetism) interaction of paper 4.1.3.3: every step, the
// force and torque that the `magnetic_forces` set computed for each magnetic
// part are queued on the rigid body, which applies them in its next advance,
// "similar to the gravity force ... until the electromagnet is turned off".
//
// It lives in resolvers/rigid_body/, the folder of the resolver it feeds, and is
// registered by register_magnetism_plugins (the later of the two physics it
// joins); it keeps the magnetism namespace of the set it reads.
//
// Contract:
//   reads    the magnetic_forces derived set (no property)
//   target   rigid_body (add_force at the centre of mass, add_torque)
//   needs    magnet
// Parts the rigid body does not move (static, pinned, without mass) get their
// force queued all the same; the rigid body decides what a load on them means.
#pragma once

#include "resolvers/magnetism/magnetic_forces.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/stage.hpp"

namespace alloy::rigid {
class RigidBodyEngine;
}

namespace alloy::magnetism {

class RigidBodyFromMagnetism : public Interaction {
 public:
  /// Plugin name.
  static constexpr const char* kName = "rigid_body_from_magnetism";

  RigidBodyFromMagnetism(rigid::RigidBodyEngine& target, const MagneticForces& forces)
      : target_(target), forces_(forces) {}
  void apply(const WorldView& world) override;

 private:
  rigid::RigidBodyEngine& target_;
  const MagneticForces& forces_;
};

/// Registers rigid_body_from_magnetism (register_magnetism_plugins does, after
/// the magnetic_forces set it reads).
void register_rigid_body_from_magnetism(PluginRegistry& registry);

}  // namespace alloy::magnetism
