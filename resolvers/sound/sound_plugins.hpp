// Registration of the sound plugins, called once from register_native_plugins
// (resolvers/plugins.cpp). Compiled into alloy_resolvers, beside the
// collisions set that sound_from_collisions reads.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::sound {

/// Registers, in this order, with their property types:
///   sound                  resolver     needs acoustic
///   sound_from_collisions  interaction  -> sound, reads collisions
/// The `collisions` set must be registered too (the interaction is
/// instantiated only when it is active).
void register_sound_plugins(PluginRegistry& registry);

}  // namespace alloy::sound
