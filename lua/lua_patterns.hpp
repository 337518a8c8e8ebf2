// Lua 5.1 string patterns with bounded work: string.find, match, gmatch and
// gsub for sandboxed states.
//
// LuaJIT's own matcher backtracks inside C, where neither the budget ticks
// (budget_ticks.hpp) nor a count hook ever run: ("a"):rep(1e5):find(".-b")
// takes quadratic time, "a-a-a-b" cubic, nested repetitions exponential, and
// a script cannot be stopped while it runs. This matcher has the same
// semantics (classes %a %c %d %g %l %p %s %u %w %x %z and their complements,
// sets, the quantifiers * + - ?, anchors, captures and position captures,
// %b, %f, back-references, gsub with string, table or function replacements
// and a maximum count) and counts its steps: one per pattern item tried, per
// character a repetition or %b scans, per 16 bytes compared or copied. A call
// that passes its allowance of steps is refused with an error naming the
// caller's file and line, and every call's steps are charged to the state's
// budget (PatternBudget), so that many small calls add up too.
//
// Plain finds (plain = true, or a pattern without magic characters) search
// with memmem, linear in the subject; their steps are charged as well.
#pragma once

#include <cstdint>
#include <string>

struct lua_State;

namespace alloy::lua {

/// How the pattern functions of one state are limited and paid for. Owned by
/// the host (lua_host.hpp); the functions keep a pointer to it.
struct PatternBudget {
  /// Steps one call (one find, match or gsub, one step of a gmatch loop) may take.
  std::uint64_t steps_per_call = 10'000'000;
  /// Who pays: called after every call with the steps it took (may raise a Lua
  /// error: the script is over its budget). Null: the steps are not counted.
  void (*charge)(void* owner, lua_State* L, std::uint64_t steps) = nullptr;
  /// Raises the error for a call over steps_per_call (and charges for it);
  /// never returns. Null: the steps are charged, then a plain Lua error at
  /// the caller's line.
  void (*refuse)(void* owner, lua_State* L, const std::string& why) = nullptr;
  void* owner = nullptr;
};

/// Sets find, match, gmatch and gsub of the table at `index` to the bounded
/// ones, limited and charged by `budget` (which must outlive the state; null:
/// the default limits, nothing charged).
void install_bounded_patterns(lua_State* L, int index, PatternBudget* budget);

}  // namespace alloy::lua
