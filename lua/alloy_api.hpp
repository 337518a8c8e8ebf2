// The `alloy` table every sandbox environment gets: small helpers that mods
// need and cannot write safely themselves.
//
//   alloy.version                the runtime's version string
//   alloy.closest(name, names)   the closest of `names` to `name`, or nil ("did you mean")
//   alloy.freeze(t)              a read-only view of t (rawset and setmetatable refuse it)
//   alloy.per_mod(f)             a module value: each mod that requires the module
//                                gets f(its name), made once (mod_loader.hpp)
#pragma once

struct lua_State;

namespace alloy::lua {

/// Pushes the (shared, frozen) alloy table.
void push_alloy_api(lua_State* L);

/// If the value at `index` was made by alloy.per_mod(f), pushes f and returns
/// true; else pushes nothing and returns false.
bool push_per_mod_function(lua_State* L, int index);

}  // namespace alloy::lua
