// The one place where C++ exceptions meet Lua errors (LÖVE's luax_catchexcept).
//
// A binding runs its C++ body inside catch_exceptions(). A C++ exception is
// caught, its message (and, for an InputError, its location) copied into Lua
// values, and only then, outside the catch block, raised as a Lua error: no
// exception object is alive while Lua unwinds. Lua errors raised inside the
// body (luaL_check*, lua_call of a script that fails) are not C++ exceptions
// of ours and pass through untouched: on x64 LuaJIT unwinds with the system
// unwinder, so destructors of the bindings' locals still run.
//
// Errors travel in Lua as "error tables" {message=, object=, file=, line=}
// with a __tostring, so that a scene's pcall sees a readable message while the
// host, at the top, still gets the object and the line separately. Mods raise
// the same shape with error({message = ..., object = ...}, 0).
#pragma once

#include <exception>
#include <lua.hpp>
#include <string>
#include <utility>

#include "lua/c_stack.hpp"
#include "runtime/error.hpp"

namespace alloy::lua {

/// An index that stays valid when the stack grows (Lua 5.2's lua_absindex).
inline int abs_index(lua_State* L, int index) {
  return (index > 0 || index <= LUA_REGISTRYINDEX) ? index : lua_gettop(L) + index + 1;
}

/// Pushes an error table for `where` and `message`.
void push_error_table(lua_State* L, const ErrorLocation& where, const std::string& message);

/// Raises the error table at the top of the stack. Never returns.
[[noreturn]] void raise_error_table(lua_State* L);

/// Runs `body` (returns the number of results); turns a C++ exception into a
/// Lua error raised after the catch block.
template <class Body>
int catch_exceptions(lua_State* L, Body&& body) {
  // A binding may read the script's tables (and so run its metamethods,
  // which may call the binding again): every binding is behind the C stack
  // guard.
  check_c_stack(L);
  ErrorLocation where;
  std::string message;
  bool failed = false;
  try {
    return std::forward<Body>(body)();
  } catch (const InputError& e) {
    where = e.where();
    message = e.bare();
    failed = true;
  } catch (const std::exception& e) {
    message = e.what();
    failed = true;
  }
  // Outside the catch block: the exception object is gone. Copy into Lua, free
  // our strings (so that nothing leaks even where Lua unwinds with longjmp),
  // and only then raise.
  if (failed) {
    push_error_table(L, where, message);
    std::string().swap(message);
    std::string().swap(where.file);
    std::string().swap(where.object);
    raise_error_table(L);
  }
  return 0;
}

/// Restores the stack top when leaving a scope, whatever the path (return,
/// exception). For host functions that must leave the stack as they found it.
class StackGuard {
 public:
  explicit StackGuard(lua_State* L) : L_(L), top_(lua_gettop(L)) {}
  ~StackGuard() { lua_settop(L_, top_); }
  StackGuard(const StackGuard&) = delete;
  StackGuard& operator=(const StackGuard&) = delete;
  int top() const { return top_; }

 private:
  lua_State* L_;
  int top_;
};

}  // namespace alloy::lua
