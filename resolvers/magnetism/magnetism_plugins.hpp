// Registration of the magnetism plugins (explicit, no static-init tricks):
//
//   magnetism                   resolver     electromagnets' pole strength from coil currents
//   magnetic_forces             derived set  poles (incl. induced) and forces/torques on parts
//   magnetism_from_electricity  interaction  coil current -> magnetism (target magnetism)
//
// and the property types of magnet_parts.hpp. Each is instantiated only when
// some object carries `magnet` (magnetism_from_electricity: and the
// electricity resolver is active), so a scene without magnets pays nothing.
// rigid_body_from_magnetism registers on its own (rigid_body_from_magnetism.hpp):
// it belongs to the rigid body and is the only magnetism code that needs it.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::magnetism {

/// Registers the three plugins and their property types. Call after the rigid
/// body's registration (it owns the geometry properties that magnetism reads;
/// magnetism registers them itself only if they are missing).
void register_magnetism_plugins(PluginRegistry& registry);

}  // namespace alloy::magnetism
