#include "lua/lua_values.hpp"

#include <algorithm>

#include "lua/lua_bridge.hpp"

namespace alloy::lua {

namespace {

SceneValue list_value(lua_State* L, int index) {
  const std::size_t n = lua_objlen(L, index);
  std::size_t keys = 0;
  for (lua_pushnil(L); lua_next(L, index); lua_pop(L, 1)) ++keys;
  if (keys != n)
    throw InputError(
        "a table here must be a list such as {1, 2} or {\"a\", \"b\"}, not a table with named "
        "fields");
  std::vector<double> numbers;
  std::vector<std::string> names;
  for (std::size_t i = 1; i <= n; ++i) {
    lua_rawgeti(L, index, int(i));
    const int type = lua_type(L, -1);
    if (type == LUA_TNUMBER && names.empty()) {
      numbers.push_back(lua_tonumber(L, -1));
    } else if (type == LUA_TSTRING && numbers.empty()) {
      names.emplace_back(lua_tostring(L, -1));
    } else {
      const std::string what = luaL_typename(L, -1);
      lua_pop(L, 1);
      throw InputError("a list must hold only numbers or only names; item " + std::to_string(i) +
                       " is a " + what);
    }
    lua_pop(L, 1);
  }
  if (!names.empty()) return names;
  return numbers;
}

}  // namespace

SceneValue to_scene_value(lua_State* L, int index) {
  index = abs_index(L, index);
  switch (lua_type(L, index)) {
    case LUA_TNUMBER:
      return lua_tonumber(L, index);
    case LUA_TBOOLEAN:
      return lua_toboolean(L, index) != 0;
    case LUA_TSTRING: {
      std::size_t n = 0;
      const char* s = lua_tolstring(L, index, &n);
      return std::string(s, n);
    }
    case LUA_TTABLE:
      return list_value(L, index);
    default:
      throw InputError(std::string("a ") + luaL_typename(L, index) + " cannot be a property value");
  }
}

std::vector<std::string> sorted_keys(lua_State* L, int index, const std::string& what) {
  index = abs_index(L, index);
  std::vector<std::string> keys;
  for (lua_pushnil(L); lua_next(L, index); lua_pop(L, 1)) {
    if (lua_type(L, -2) != LUA_TSTRING) {
      lua_pop(L, 2);
      throw InputError(what +
                       " must be given as name = value; found a value without a name "
                       "(a list item?)");
    }
    keys.emplace_back(lua_tostring(L, -2));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

}  // namespace alloy::lua
