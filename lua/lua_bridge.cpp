#include "lua/lua_bridge.hpp"

namespace alloy::lua {

namespace {

constexpr const char* kErrorMetatable = "alloy.error";

// __tostring of an error table: the same text InputError would print.
int error_tostring(lua_State* L) {
  ErrorLocation where;
  std::string message;
  lua_getfield(L, 1, "message");
  if (const char* s = lua_tostring(L, -1)) message = s;
  lua_getfield(L, 1, "object");
  if (const char* s = lua_tostring(L, -1)) where.object = s;
  lua_getfield(L, 1, "file");
  if (const char* s = lua_tostring(L, -1)) where.file = s;
  lua_getfield(L, 1, "line");
  where.line = int(lua_tointeger(L, -1));
  lua_pop(L, 4);
  const std::string text = InputError::format(where, message);
  lua_pushlstring(L, text.data(), text.size());
  return 1;
}

void set_string(lua_State* L, const char* key, const std::string& value) {
  if (value.empty()) return;
  lua_pushlstring(L, value.data(), value.size());
  lua_setfield(L, -2, key);
}

}  // namespace

void push_error_table(lua_State* L, const ErrorLocation& where, const std::string& message) {
  lua_createtable(L, 0, 4);
  set_string(L, "message", message);
  set_string(L, "object", where.object);
  set_string(L, "file", where.file);
  if (where.line > 0) {
    lua_pushinteger(L, where.line);
    lua_setfield(L, -2, "line");
  }
  if (luaL_newmetatable(L, kErrorMetatable)) {
    lua_pushcfunction(L, error_tostring);
    lua_setfield(L, -2, "__tostring");
  }
  lua_setmetatable(L, -2);
}

void raise_error_table(lua_State* L) {
  lua_error(L);
  __builtin_unreachable();
}

}  // namespace alloy::lua
