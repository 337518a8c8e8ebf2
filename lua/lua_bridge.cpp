#include "lua/lua_bridge.hpp"

#include <cstdlib>

namespace alloy::lua {

namespace {

constexpr const char* kErrorMetatable = "alloy.error";

// The string (or number) in field `key` of the table at 1, read raw: this
// runs with C++ strings alive, and no code of a script may run meanwhile.
void raw_text(lua_State* L, const char* key, std::string& out) {
  lua_pushstring(L, key);
  lua_rawget(L, 1);
  const int t = lua_type(L, -1);
  if (t == LUA_TSTRING || t == LUA_TNUMBER) {
    std::size_t n = 0;
    const char* s = lua_tolstring(L, -1, &n);  // a copy on the stack: the table is not changed
    out.assign(s, n);
  }
  lua_pop(L, 1);
}

// __tostring of an error table: the same text InputError would print.
int error_tostring(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  ErrorLocation where;
  std::string message, line;
  raw_text(L, "message", message);
  raw_text(L, "object", where.object);
  raw_text(L, "file", where.file);
  raw_text(L, "line", line);
  where.line = std::atoi(line.c_str());
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
    // Hidden from scripts: getmetatable(err) must not hand out the host's
    // metatable, to change for every error the state raises.
    lua_pushliteral(L, "error");
    lua_setfield(L, -2, "__metatable");
  }
  lua_setmetatable(L, -2);
}

void raise_error_table(lua_State* L) {
  lua_error(L);
  __builtin_unreachable();
}

}  // namespace alloy::lua
