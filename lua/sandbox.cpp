#include "lua/sandbox.hpp"

#include <cstdint>
#include <cstring>
#include <lua.hpp>
#include <string>

#include "lua/c_stack.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/lua_patterns.hpp"

namespace alloy::lua {

namespace {

// Base functions a script may use. Everything else of the base library stays
// out (file access, environments, the collector, bytecode).
constexpr const char* kBaseWhitelist[] = {
    "assert",   "error",  "ipairs",   "next",         "pairs",        "pcall",
    "xpcall",   "select", "tonumber", "tostring",     "type",         "unpack",
    "rawequal", "rawget", "print",    "setmetatable", "getmetatable", "_VERSION",
};

// Libraries copied into each environment. string.dump is removed from the
// original table in prepare_state (strings reach it through their metatable).
constexpr const char* kLibraries[] = {"string", "table", "math", "bit", "coroutine"};

constexpr const char* kFrozenSet = "alloy.frozen";

void open(lua_State* L, lua_CFunction opener, const char* name) {
  lua_pushcfunction(L, opener);
  lua_pushstring(L, name);
  lua_call(L, 1, 0);
}

// load(chunk [, chunkname [, mode [, env]]]) for scripts: source text only,
// compiled into the caller's environment unless one is given.
int safe_load(lua_State* L) {
  std::size_t size = 0;
  const char* code = lua_tolstring(L, 1, &size);
  if (lua_type(L, 1) != LUA_TSTRING)
    return luaL_error(L, "load: only source text can be loaded in the sandbox");
  if (!lua_isnoneornil(L, 3)) {
    const char* mode = luaL_checkstring(L, 3);
    if (std::strcmp(mode, "t") != 0)
      return luaL_error(L, "load: only text chunks may be loaded (mode \"t\"), not \"%s\"", mode);
  }
  // A script may not pose as one of the host's files: its chunk names are
  // always literal ("=name"), never file names ("@file").
  std::string name = "=";
  if (const char* n = lua_tostring(L, 2))
    name += (n[0] == '@' || n[0] == '=') ? n + 1 : n;
  else
    name += "(load)";
  // Through the host, so that a mod's loaded text gets the same budget ticks
  // as its files.
  LuaHost* host = LuaHost::from(L);
  const bool ok = host ? host->compile(std::string_view(code, size), name)
                       : luaL_loadbufferx(L, code, size, name.c_str(), "t") == 0;
  if (!ok) {
    lua_pushnil(L);
    lua_insert(L, -2);
    return 2;  // nil, message: as load does
  }
  if (lua_type(L, 4) == LUA_TTABLE) {
    lua_pushvalue(L, 4);
  } else {
    lua_Debug ar;
    if (!lua_getstack(L, 1, &ar) || !lua_getinfo(L, "f", &ar))
      return luaL_error(L, "load: no calling function to take the environment from");
    lua_getfenv(L, -1);
    lua_remove(L, -2);
  }
  lua_setfenv(L, -2);
  return 1;
}

int safe_rawset(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  luaL_checkany(L, 2);
  luaL_checkany(L, 3);
  // A locked metatable (a __metatable field) is what setmetatable refuses, and
  // rawset refuses the same tables: the frozen proxies, and the tables the
  // host's Lua code made with a locked metatable (vec3, quat, a stage's view,
  // its target and settings), which the frozen set does not hold.
  bool locked = false;
  if (lua_getmetatable(L, 1)) {
    lua_pushliteral(L, "__metatable");
    lua_rawget(L, -2);
    locked = !lua_isnil(L, -1);
    lua_pop(L, 2);
  }
  if (locked || is_frozen(L, 1))
    return luaL_error(L, "rawset: this table belongs to the host and is read-only");
  lua_settop(L, 3);
  lua_rawset(L, 1);
  lua_settop(L, 1);
  return 1;
}

// A library function that can call back into Lua, behind the C stack guard.
// Upvalue 1: the original function, called with all arguments and results.
int guarded_call(lua_State* L) {
  check_c_stack(L);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  return lua_gettop(L);
}

// coroutine.wrap, whose result resumes the coroutine when called: guarded too.
int guarded_wrap(lua_State* L) {
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, 1);
  lua_pushcclosure(L, guarded_call, 1);
  return 1;
}

/// Replaces table[name] (the table at `t`) by `wrapper` over the original.
void guard(lua_State* L, int t, const char* name, lua_CFunction wrapper = guarded_call) {
  lua_getfield(L, t, name);
  lua_pushcclosure(L, wrapper, 1);
  lua_setfield(L, t, name);
}

// The Lua instructions a caught error is counted as: about what it costs
// against an interpreted instruction (session 12, Release: a caught error
// about 2 us, an instruction about 1.5 ns). A scene looping on a caught
// error ran into the 20 s wall limit before its 2e9 instructions were spent;
// now it is stopped after 2.1 s, sooner than a plain endless loop (3.0 s).
// docs/security.md, "Bounded C work".
constexpr std::uint64_t kCaughtErrorCost = 2000;

int charge_caught_error(lua_State* L) {
  if (LuaHost* host = LuaHost::from(L)) host->charge_work(L, kCaughtErrorCost);
  return 0;
}

int refuse_write(lua_State* L) {
  const char* key = lua_tostring(L, 2);
  return luaL_error(L, "this table is read-only (cannot set '%s')", key ? key : "?");
}

}  // namespace

void prepare_state(lua_State* L, PatternBudget* patterns) {
  open(L, luaopen_base, "");
  open(L, luaopen_string, LUA_STRLIBNAME);
  open(L, luaopen_table, LUA_TABLIBNAME);
  open(L, luaopen_math, LUA_MATHLIBNAME);
  open(L, luaopen_bit, LUA_BITLIBNAME);
  open(L, luaopen_jit, LUA_JITLIBNAME);  // initialises and enables the compiler

  // string.dump would hand out bytecode; remove it from the one real string
  // table (also the __index of every string).
  lua_getglobal(L, "string");
  lua_pushnil(L);
  lua_setfield(L, -2, "dump");
  // Patterns whose work is bounded and charged; format (%s calls __tostring)
  // behind the C stack guard.
  install_bounded_patterns(L, -1, patterns);
  guard(L, lua_gettop(L), "format");
  lua_pop(L, 1);
  // The other C functions that call back into Lua: comparators, __tostring,
  // coroutines (each with a Lua stack of its own, so that only the C stack
  // bounds their nesting). pcall, xpcall and metamethods called by the VM
  // keep no C frame in LuaJIT.
  lua_pushvalue(L, LUA_GLOBALSINDEX);
  guard(L, lua_gettop(L), "tostring");
  lua_pop(L, 1);
  lua_getglobal(L, "table");
  guard(L, lua_gettop(L), "sort");
  lua_pop(L, 1);
  lua_getglobal(L, "coroutine");
  guard(L, lua_gettop(L), "resume");
  guard(L, lua_gettop(L), "wrap", guarded_wrap);
  lua_pop(L, 1);

  // pcall and xpcall charge each error they catch to the script's budget.
  // An error costs the host far more than the few instructions the count
  // hook sees (a message built, the stack unwound). The wrappers are Lua functions over the
  // originals, so a coroutine may still yield through them.
  static const char kCatching[] =
      "local raw_pcall, raw_xpcall, charge = ...\n"
      "local function after(ok, ...)\n"
      "  if not ok then charge() end\n"
      "  return ok, ...\n"
      "end\n"
      "return function(f, ...) return after(raw_pcall(f, ...)) end,\n"
      "       function(f, handler, ...) return after(raw_xpcall(f, handler, ...)) end\n";
  if (luaL_loadbuffer(L, kCatching, sizeof kCatching - 1, "=pcall") != 0) lua_error(L);
  lua_getglobal(L, "pcall");
  lua_getglobal(L, "xpcall");
  lua_pushcfunction(L, charge_caught_error);
  lua_call(L, 3, 2);
  lua_setglobal(L, "xpcall");
  lua_setglobal(L, "pcall");

  // getmetatable("") would reach that real table; __metatable hides it.
  lua_pushliteral(L, "");
  if (lua_getmetatable(L, -1)) {
    lua_pushboolean(L, 0);
    lua_setfield(L, -2, "__metatable");
    lua_pop(L, 1);
  }
  lua_pop(L, 1);

  // The set of frozen proxies, weak so that it keeps none alive.
  lua_newtable(L);
  lua_newtable(L);
  lua_pushliteral(L, "k");
  lua_setfield(L, -2, "__mode");
  lua_setmetatable(L, -2);
  lua_setfield(L, LUA_REGISTRYINDEX, kFrozenSet);
}

void push_environment(lua_State* L) {
  lua_newtable(L);
  const int env = lua_gettop(L);
  for (const char* name : kBaseWhitelist) {
    lua_getglobal(L, name);
    lua_setfield(L, env, name);
  }
  for (const char* lib : kLibraries) {
    lua_newtable(L);
    lua_getglobal(L, lib);
    for (lua_pushnil(L); lua_next(L, -2);) {
      lua_pushvalue(L, -2);
      lua_insert(L, -2);
      lua_settable(L, -5);  // copy[key] = value
    }
    lua_pop(L, 1);
    lua_setfield(L, env, lib);
  }
  lua_pushcfunction(L, safe_load);
  lua_setfield(L, env, "load");
  lua_pushcfunction(L, safe_rawset);
  lua_setfield(L, env, "rawset");
  lua_pushvalue(L, env);
  lua_setfield(L, env, "_G");
}

void push_frozen(lua_State* L, int index) {
  index = abs_index(L, index);
  lua_newtable(L);  // the proxy: always empty, so every write reaches __newindex
  lua_createtable(L, 0, 3);
  lua_pushvalue(L, index);
  lua_setfield(L, -2, "__index");
  lua_pushcfunction(L, refuse_write);
  lua_setfield(L, -2, "__newindex");
  lua_pushliteral(L, "read-only");
  lua_setfield(L, -2, "__metatable");  // setmetatable refuses, getmetatable hides
  lua_setmetatable(L, -2);
  lua_getfield(L, LUA_REGISTRYINDEX, kFrozenSet);
  lua_pushvalue(L, -2);
  lua_pushboolean(L, 1);
  lua_rawset(L, -3);
  lua_pop(L, 1);
}

bool is_frozen(lua_State* L, int index) {
  index = abs_index(L, index);
  lua_getfield(L, LUA_REGISTRYINDEX, kFrozenSet);
  lua_pushvalue(L, index);
  lua_rawget(L, -2);
  const bool frozen = lua_toboolean(L, -1);
  lua_pop(L, 2);
  return frozen;
}

}  // namespace alloy::lua
