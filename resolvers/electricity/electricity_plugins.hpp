// Registration of the electricity plugins, called once from
// register_native_plugins (resolvers/plugins.cpp). Built with electricity's
// plugins library, which links the rigid body (the collisions set) and
// magnetism (the magnetic_forces set) that the interactions of this folder read.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::electricity {

/// Registers, in this order, with their property types:
///   electricity                  resolver     needs emf or inductance
///   electricity_from_collisions  interaction  -> electricity, reads collisions
/// electricity_from_magnetism lives here too (it feeds electricity) and
/// registers with magnetism, the later of the two physics it joins;
/// electricity_from_light likewise with light (resolvers/light/).
void register_electricity_plugins(PluginRegistry& registry);

}  // namespace alloy::electricity
