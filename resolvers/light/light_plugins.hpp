// Registration of the light plugins, called once from register_native_plugins
// (resolvers/plugins.cpp). Built with light's plugins library, which links
// electricity (the two interactions queue on it and read it).
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::light {

/// Registers, in this order, with their property types:
///   light                   resolver     needs luminous_efficacy or light_receiver
///   illuminance             derived set  needs light_receiver
///   light_from_electricity  interaction  -> light, with electricity active
///   electricity_from_light  interaction  -> electricity, reads illuminance
void register_light_plugins(PluginRegistry& registry);

}  // namespace alloy::light
