#include "resolvers/rigid_body/rigid_body_from_magnetism.hpp"

#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/rigid_body/engine.hpp"

namespace alloy::magnetism {

void RigidBodyFromMagnetism::apply(const WorldView& world) {
  const PropertyStore& store = world.store();
  for (const MagneticBody& b : forces_.bodies()) {
    // The set was updated this step or, if skipped, its inputs did not change;
    // either way its parts are alive unless one was destroyed since.
    if (!store.alive(b.id)) continue;
    if (forces_.rates()) {
      // With rates the rigid body follows the load over its substeps.
      if (!(b.force == Vec3{} && b.torque == Vec3{}))
        target_.add_load(b.id, b.force, b.torque, b.force_rate, b.torque_rate);
      continue;
    }
    if (!(b.force == Vec3{})) target_.add_force(b.id, b.force);
    if (!(b.torque == Vec3{})) target_.add_torque(b.id, b.torque);
  }
}

void register_rigid_body_from_magnetism(PluginRegistry& registry) {
  registry.add({
      .info = {.name = RigidBodyFromMagnetism::kName,
               .kind = StageKind::Interaction,
               .needs = {prop::kMagnet},
               .derived = {MagneticForces::kName},
               .target = "rigid_body",
               .doc = "magnetic forces and torques move the parts"},
      .create =
          [](PluginContext& ctx) {
            return std::make_unique<RigidBodyFromMagnetism>(
                ctx.target<rigid::RigidBodyEngine>(),
                ctx.dependency<MagneticForces>(MagneticForces::kName));
          },
  });
}

}  // namespace alloy::magnetism
