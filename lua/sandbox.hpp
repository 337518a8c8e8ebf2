// The sandbox: what scene and mod code may touch.
//
// A state is prepared once (prepare_state): only the harmless libraries are
// opened (base, string, table, math, bit; jit only to switch the compiler on),
// string.dump is removed, and the string metatable is hidden. The state's real
// globals are never given to a script: each mod and each scene runs with an
// environment table of its own (push_environment) that holds copies of
// whitelisted functions and libraries and nothing else:
//
//   no io, os, debug, ffi, jit, package; no dofile, loadfile, loadstring,
//   getfenv, setfenv, collectgarbage, newproxy, module, gcinfo, string.dump;
//   load compiles text only (mode "t") into the caller's environment;
//   rawset refuses host tables (frozen ones, and any table whose metatable is
//   locked with __metatable, as setmetatable does); require is the mod loader's.
//
// Library tables are copied per environment, so a mod that changes
// `string.format` changes it for itself only.
//
// Work a script makes C do is bounded too: string.find, match, gmatch and gsub
// (also as methods of strings) are the host's own matcher, which counts its
// steps against the state's budget (lua_patterns.hpp); the C functions that
// call back into Lua (gsub, table.sort, tostring, string.format,
// coroutine.resume and wrap) check the depth of the C stack first
// (c_stack.hpp), so that recursion through them ends in a Lua error, not in
// a crash.
#pragma once

struct lua_State;

namespace alloy::lua {

struct PatternBudget;

/// Opens the safe libraries in a fresh state. Call once, before any script.
/// `patterns` limits and charges the pattern functions (it must outlive the
/// state; null: default limits, nothing charged).
void prepare_state(lua_State* L, PatternBudget* patterns = nullptr);

/// Pushes a new sandbox environment table (without the host API: the scene
/// bindings and the mod loader add theirs).
void push_environment(lua_State* L);

/// Replaces the table at `index` by a read-only proxy of it, marked as a host
/// table (rawset and setmetatable refuse it). Leaves the proxy on the stack
/// top, the original table stays where it was.
void push_frozen(lua_State* L, int index);

/// True if the value at `index` is a frozen proxy.
bool is_frozen(lua_State* L, int index);

}  // namespace alloy::lua
