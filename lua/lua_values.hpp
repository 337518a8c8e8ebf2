// Reading script values into plain C++ (SceneValue): numbers, booleans,
// strings, and lists of numbers or of names. Anything else (functions, nested
// tables, tables with named fields where a list is expected) is refused with a
// message that says what was written.
#pragma once

#include <string>
#include <vector>

#include "lua/scene_record.hpp"

struct lua_State;

namespace alloy::lua {

/// The value at `index`. Throws InputError (without a location) if it has no
/// SceneValue form.
SceneValue to_scene_value(lua_State* L, int index);

/// The string keys of the table at `index`, sorted (a deterministic order for
/// applying and for the first error reported). Throws on a non-string key.
std::vector<std::string> sorted_keys(lua_State* L, int index, const std::string& what);

}  // namespace alloy::lua
