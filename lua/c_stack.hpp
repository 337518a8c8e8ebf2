// A limit on how deep script code may nest C functions that call back into
// Lua (string.gsub with a function, table.sort with a comparator, tostring and
// string.format with a __tostring, coroutine.resume and wrap, the host's
// bindings reading a table with metamethods).
//
// LuaJIT bounds the Lua stack of each coroutine, but not the C stack: each of
// those calls puts C frames on the one real stack of the thread, and a script
// that recurses through them (`local function f() return (string.gsub("a",
// "a", f)) end f()`, or a chain of coroutines, each with a fresh Lua stack)
// ends in SIGSEGV. The guard measures the real C stack: where the host
// entered Lua (CStackEntry, in LuaHost::call) against the address of the
// guard's own frame, and the distance left to the end of the thread's stack.
// Past either limit it raises a Lua error at the script's line, long before
// the stack ends. Measuring bytes rather than counting calls needs no
// bookkeeping that an error could skip, and holds for frames of any size.
#pragma once

#include <cstddef>

struct lua_State;

namespace alloy::lua {

/// C stack the script's calls may use below the host's entry into Lua.
inline constexpr std::size_t kCStackLimit = 1u << 20;
/// C stack always left free at the end of the thread's stack (for the error
/// raised there and its handler).
inline constexpr std::size_t kCStackReserve = 256u << 10;

/// Raises "C stack limit: ..." (a Lua error at the caller's line) when the
/// current C stack is past either limit. For C functions that call into Lua.
void check_c_stack(lua_State* L);

/// Records the current position of the C stack as the host's entry into Lua,
/// for the lifetime of the object (nested entries restore the outer one).
class CStackEntry {
 public:
  CStackEntry();
  ~CStackEntry();
  CStackEntry(const CStackEntry&) = delete;
  CStackEntry& operator=(const CStackEntry&) = delete;

 private:
  const char* previous_;
};

}  // namespace alloy::lua
