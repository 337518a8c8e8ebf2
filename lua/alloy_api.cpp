#include "lua/alloy_api.hpp"

#include <string>
#include <vector>

#include "lua/lua_bridge.hpp"
#include "lua/sandbox.hpp"
#include "runtime/property_types.hpp"

namespace alloy::lua {

namespace {

constexpr const char* kApiKey = "alloy.api";
constexpr const char* kPerModKey = "alloy.per_mod";  // the metatable of per_mod values

// alloy.per_mod(f): { f } under a locked metatable of the host's own, which
// the loader recognises (push_per_mod_function); a script cannot change f.
int per_mod(lua_State* L) {
  luaL_checktype(L, 1, LUA_TFUNCTION);
  lua_createtable(L, 1, 0);
  lua_pushvalue(L, 1);
  lua_rawseti(L, -2, 1);
  lua_getfield(L, LUA_REGISTRYINDEX, kPerModKey);
  if (lua_isnil(L, -1)) {
    lua_pop(L, 1);
    lua_createtable(L, 0, 2);
    lua_pushliteral(L, "per_mod");
    lua_setfield(L, -2, "__metatable");
    lua_pushvalue(L, -1);
    lua_setfield(L, LUA_REGISTRYINDEX, kPerModKey);
  }
  lua_setmetatable(L, -2);
  return 1;
}

int closest(lua_State* L) {
  return catch_exceptions(L, [&] {
    const char* name = luaL_checkstring(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    std::vector<std::string> names;
    for (int i = 1;; ++i) {
      lua_rawgeti(L, 2, i);
      if (lua_isnil(L, -1)) break;
      if (lua_type(L, -1) == LUA_TSTRING) names.emplace_back(lua_tostring(L, -1));
      lua_pop(L, 1);
    }
    const std::string best = closest_name(name, names);
    if (best.empty())
      lua_pushnil(L);
    else
      lua_pushlstring(L, best.data(), best.size());
    return 1;
  });
}

int freeze(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  if (is_frozen(L, 1)) {
    lua_settop(L, 1);
    return 1;
  }
  push_frozen(L, 1);
  return 1;
}

}  // namespace

void push_alloy_api(lua_State* L) {
  lua_getfield(L, LUA_REGISTRYINDEX, kApiKey);
  if (!lua_isnil(L, -1)) return;
  lua_pop(L, 1);
  lua_createtable(L, 0, 4);
  lua_pushliteral(L, "0.1.0");
  lua_setfield(L, -2, "version");
  lua_pushcfunction(L, closest);
  lua_setfield(L, -2, "closest");
  lua_pushcfunction(L, freeze);
  lua_setfield(L, -2, "freeze");
  lua_pushcfunction(L, per_mod);
  lua_setfield(L, -2, "per_mod");
  push_frozen(L, -1);
  lua_remove(L, -2);
  lua_pushvalue(L, -1);
  lua_setfield(L, LUA_REGISTRYINDEX, kApiKey);
}

bool push_per_mod_function(lua_State* L, int index) {
  index = abs_index(L, index);
  if (lua_type(L, index) != LUA_TTABLE || !lua_getmetatable(L, index)) return false;
  lua_getfield(L, LUA_REGISTRYINDEX, kPerModKey);
  const bool ours = lua_rawequal(L, -1, -2);
  lua_pop(L, 2);
  if (!ours) return false;
  lua_rawgeti(L, index, 1);
  return true;
}

}  // namespace alloy::lua
