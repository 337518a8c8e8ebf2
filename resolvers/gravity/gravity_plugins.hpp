// Registration of the gravity plugins, called once from register_native_plugins
// (resolvers/plugins.cpp). The force they lead to is rigid_body_from_gravity,
// in resolvers/rigid_body/ (the folder of the resolver it feeds); gravity
// registers it, as the later of the two physics it joins.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::gravity {

/// Registers, in this order, with their property types (both provide
/// "gravity"; the first registered is the default provider):
///   gravity.uniform          resolver     needs mass or density
///   gravity.nbody            resolver     needs mass or density
///   rigid_body_from_gravity  interaction  -> rigid_body, reads gravity
void register_gravity_plugins(PluginRegistry& registry);

/// Each plugin's definition on its own, for registries that take a few.
PluginDef uniform_gravity_plugin();
PluginDef nbody_gravity_plugin();

}  // namespace alloy::gravity
