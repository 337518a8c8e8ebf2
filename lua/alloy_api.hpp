// The `alloy` table every sandbox environment gets: small helpers that mods
// need and cannot write safely themselves.
//
//   alloy.version                the runtime's version string
//   alloy.closest(name, names)   the closest of `names` to `name`, or nil ("did you mean")
//   alloy.freeze(t)              a read-only view of t (rawset and setmetatable refuse it)
#pragma once

struct lua_State;

namespace alloy::lua {

/// Pushes the (shared, frozen) alloy table.
void push_alloy_api(lua_State* L);

}  // namespace alloy::lua
