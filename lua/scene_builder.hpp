// The second half of loading (collect, then apply): a SceneRecord becomes a
// WorldDef and a World with its objects. Every value is typed against the
// property registry and checked (the owners' bounds on PropertyDef, and each
// plugin's whole-object check through World::check) here, before any resolver
// exists; any error is reported at the scene line that recorded the object.
// Nothing here knows Lua.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "lua/scene_record.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

struct BuiltScene {
  WorldDef def;
  std::unique_ptr<World> world;
  /// Where each named object was defined.
  std::map<std::string, ErrorLocation, std::less<>> sources;
};

/// Throws InputError naming the file, the line and the object.
BuiltScene build_scene(const SceneRecord& record, PluginRegistry& registry);

/// The property value a scene value stands for, given the property's type.
/// Refs are resolved by name in `world`. Throws InputError without a location.
PropertyValue to_property_value(const SceneValue& value, const PropertyDef& def,
                                const World& world);

}  // namespace alloy::lua
