// The time budget of a mod, made to hold under LuaJIT's JIT compiler.
//
// A count hook (lua_sethook) does not fire inside compiled traces: a mod's
// `while true do end` is compiled after a few dozen iterations and then runs
// forever in machine code. Turning the JIT off would make every Lua stage
// 10-50 times slower. Instead the host rewrites a mod's source before it
// compiles it, adding one call of a budget check ("tick") at the top of every
// loop body and every function body:
//
//   while true do __alloy_tick(); end
//   local function f(a) __alloy_tick(); return a end
//
// The tick is a counter decrement that the JIT compiles inline; once every
// few thousand ticks it calls the host, which checks the mod's budgets (ticks
// and wall-clock time per step, memory) and raises an error naming the mod's
// file and line when one is spent. Once a mod is over budget every tick fails,
// so a pcall around the loop cannot swallow the stop. Line numbers are kept:
// insertions never add a line break.
//
// This file only rewrites text; it knows nothing of Lua states.
#pragma once

#include <string>
#include <string_view>

namespace alloy::lua {

/// The name of the tick function inside instrumented code. A mod may not use it.
inline constexpr std::string_view kTickName = "__alloy_tick";

/// Adds a tick call after every `do`, `repeat`, goto label `::name::` and
/// function parameter list of `source`, and wraps the result as
///
///   return function(__alloy_tick) return function(...) <source>
///   end end
///
/// so that loading it and calling the result with the tick function gives a
/// function that behaves as the original chunk, with the tick as an upvalue
/// no script can reach. Throws InputError at `display` and the line if the
/// source names __alloy_tick itself. Syntax errors are left to the compiler
/// (the lexer is lenient and never fails on them).
std::string add_budget_ticks(std::string_view source, const std::string& display);

}  // namespace alloy::lua
