// The plugin registry the Lua tests load scenes into: the native plugins when
// resolvers/ provides them, otherwise stand-ins that register the same
// property types (the contract of resolvers/plugins.hpp) and plugin names, so
// that the loader is tested against the names the real plugins use.
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::test {

void register_scene_plugins(PluginRegistry& registry);

}  // namespace alloy::test
