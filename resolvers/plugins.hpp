// Registration of every native plugin (resolvers/, no Lua): called explicitly
// by whoever makes a PluginRegistry (the Lua host, the apps, tests, benchmarks).
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy {

/// Registers, in this order (the order stages run in when nothing else decides):
///   rigid_body                  resolver (ODE)        needs mass or density
///   collisions                  derived set (ODE collision detection)
///   rigid_body_from_collisions  interaction -> rigid_body
///   gravity.uniform             resolver              needs mass or density
///   rigid_body_from_gravity     interaction -> rigid_body
///   electricity, electricity_from_collisions
///                               (resolvers/electricity/; need emf or inductance)
///   magnetism, magnetic_forces, magnetism_from_electricity, rigid_body_from_magnetism
///                               (resolvers/magnetism/; need magnet, or current)
///   sound, sound_from_collisions
///                               (resolvers/sound/; need acoustic)
///   light, illuminance, light_from_electricity, electricity_from_light
///                               (resolvers/light/; need luminous_efficacy or light_receiver)
/// and the property types they define.
void register_native_plugins(PluginRegistry& registry);

namespace rigid {
PluginDef rigid_body_plugin();
PluginDef collisions_plugin();
PluginDef rigid_body_from_collisions_plugin();
PluginDef rigid_body_from_gravity_plugin();
}  // namespace rigid
namespace gravity {
PluginDef uniform_gravity_plugin();
}  // namespace gravity

}  // namespace alloy
