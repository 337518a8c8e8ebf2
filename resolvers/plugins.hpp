// Registration of every native plugin (resolvers/, no Lua): called explicitly
// by whoever makes a PluginRegistry (the Lua host, the apps, tests, benchmarks).
#pragma once

#include "resolvers/gravity/gravity_plugins.hpp"
#include "resolvers/rigid_body/rigid_body_plugins.hpp"
#include "runtime/plugin_registry.hpp"

namespace alloy {

/// Registers each physics folder's plugins with its register_<physics>_plugins,
/// in the order of resolvers/CMakeLists.txt's list (the order stages run in
/// when nothing else decides; an interaction registers with the later of the
/// two physics it joins):
///   rigid_body, collisions, rigid_body_from_collisions
///                                      (resolvers/rigid_body/; need mass or density)
///   gravity.uniform, gravity.nbody, rigid_body_from_gravity
///                                      (resolvers/gravity/; need mass or density)
///   electricity, electricity_from_collisions
///                                      (resolvers/electricity/; need emf or inductance)
///   magnetism, magnetic_forces, magnetism_from_electricity,
///   rigid_body_from_magnetism, electricity_from_magnetism
///                                      (resolvers/magnetism/; need magnet, or current)
///   sound, sound_from_collisions       (resolvers/sound/; need acoustic)
///   light, illuminance, light_from_electricity, electricity_from_light
///                                      (resolvers/light/; need luminous_efficacy or
///                                      light_receiver)
/// and the property types they define.
void register_native_plugins(PluginRegistry& registry);

}  // namespace alloy
