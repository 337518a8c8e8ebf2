// Registration of the magnetism plugins (explicit, no static-init tricks):
//
//   magnetism                   resolver     electromagnets' pole strength from coil currents
//   magnetic_forces             derived set  poles (incl. induced) and forces/torques on parts
//   magnetism_from_electricity  interaction  coil current -> magnetism (target magnetism)
//
// and the property types of magnet_parts.hpp. Each is instantiated only when
// some object carries `magnet` (magnetism_from_electricity: and the
// electricity resolver is active), so a scene without magnets pays nothing.
// The interactions between magnetism and the physics registered before it
// live with the resolvers they feed (rigid_body_from_magnetism in
// resolvers/rigid_body/, electricity_from_magnetism in resolvers/electricity/);
// register_magnetism_plugins registers them, after magnetism's own plugins,
// because an interaction registers with the later of the two physics it joins.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::magnetism {

/// Registers the three plugins above and their property types: magnetism on its
/// own, for tests and tools without the rigid body and electricity.
void register_magnetism_resolver(PluginRegistry& registry);

/// Registers, in this order: the three plugins above (register_magnetism_resolver),
/// rigid_body_from_magnetism (-> rigid_body) and electricity_from_magnetism
/// (-> electricity). Call after the rigid body's registration (it owns the
/// geometry properties that magnetism reads; magnetism registers them itself
/// only if they are missing) and electricity's.
void register_magnetism_plugins(PluginRegistry& registry);

}  // namespace alloy::magnetism
