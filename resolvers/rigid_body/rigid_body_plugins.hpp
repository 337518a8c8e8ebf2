// Registration of the rigid-body plugins, called once from
// register_native_plugins (resolvers/plugins.cpp). Built with the rigid body's
// plugins library, which links gravity (the `gravity` property) and magnetism
// (the magnetic_forces set) that the interactions of this folder read.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::rigid {

/// Registers, in this order, with their property types:
///   rigid_body                  resolver (ODE)  needs mass or density
///   collisions                  derived set     (ODE collision detection)
///   rigid_body_from_collisions  interaction     -> rigid_body, contact joints
/// The other interactions that feed the rigid body live in this folder too and
/// register with the later physics they join: rigid_body_from_gravity with
/// gravity, rigid_body_from_magnetism with magnetism.
void register_rigid_body_plugins(PluginRegistry& registry);

/// Each plugin's definition on its own, for registries that take a few
/// (bench/rigid_overhead.cpp builds the bare rigid body).
PluginDef rigid_body_plugin();
PluginDef collisions_plugin();
PluginDef rigid_body_from_collisions_plugin();
PluginDef rigid_body_from_gravity_plugin();

}  // namespace alloy::rigid
