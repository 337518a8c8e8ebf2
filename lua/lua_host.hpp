// One LuaJIT state and everything needed to run untrusted script code in it
// safely: a counting allocator, text-only loading, protected calls with a
// traceback handler, and the mapping of a Lua error to an InputError that
// names the file, the line and the object.
//
// One host per use (a scene load, later a running mod set); there is no
// global state. The host is not a core class: the world and the resolvers
// never see it.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include "lua/lua_patterns.hpp"
#include "lua/memory_budget.hpp"
#include "runtime/error.hpp"

struct lua_State;
struct lua_Debug;

namespace alloy::lua {

struct HostOptions {
  /// Bytes the state may hold; 0 = no limit.
  std::size_t memory_limit = 0;
  /// Lua VM instructions one call() may run; 0 = no limit. Setting it turns
  /// the JIT compiler off: count hooks do not run inside compiled code. Right
  /// for loading scenes (run once); a per-step budget for Lua stages will
  /// need another mechanism.
  std::uint64_t instruction_limit = 0;
  /// Wall-clock seconds one outermost call() may take; 0 = no limit. Checked
  /// with the instruction budget (so only with instruction_limit > 0) and
  /// whenever C work is charged.
  double seconds_limit = 0;
  /// Steps one call of a pattern function may take (lua_patterns.hpp). About
  /// 0.1 s of matching: enough for ordinary patterns over megabytes of text,
  /// far less than a backtracking bomb takes.
  std::uint64_t pattern_steps = 10'000'000;
};

/// Who pays for the C work a script makes the host do (pattern matching):
/// a mod's runtime charges it to the mod's tick budget and stops the mod
/// when it is spent. Without an account the host charges it as instructions
/// against HostOptions::instruction_limit and seconds_limit.
struct WorkAccount {
  /// Pays for `steps` of C work; may raise a Lua error (the budget is spent).
  std::function<void(lua_State* L, std::uint64_t steps)> charge;
  /// Raises the error for one call over its allowance (`why` says which);
  /// must not return.
  std::function<void(lua_State* L, const std::string& why)> refuse;
};

class LuaHost {
 public:
  explicit LuaHost(HostOptions options = {});
  ~LuaHost();
  LuaHost(const LuaHost&) = delete;
  LuaHost& operator=(const LuaHost&) = delete;

  lua_State* state() const { return L_; }
  const MemoryBudget& memory() const { return *budget_; }
  MemoryBudget& memory() { return *budget_; }

  /// Reads a Lua source file and pushes it as a function (text only: a
  /// precompiled chunk is refused). `display` is the name used in messages.
  /// A syntax error throws InputError at the file and line.
  void load_file(const std::filesystem::path& file, const std::string& display);
  /// Same for source text in memory (tests, generated code).
  void load_string(std::string_view code, const std::string& display);

  /// Compiles source text (never bytecode) under `chunkname` ("@file" or
  /// "=name"), applying the budget ticks if they are on. Pushes the function
  /// and returns true, or pushes the error message and returns false. For
  /// the sandbox's load(), which must not throw.
  bool compile(std::string_view code, const std::string& chunkname);

  /// From now on every chunk this host compiles gets budget ticks
  /// (budget_ticks.hpp) calling `tick`, the function at `index`: the way to
  /// stop a runaway loop that the JIT compiled. The JIT stays on.
  void use_budget_ticks(int index);
  bool budget_ticks() const { return ticks_ref_ != -2; }

  /// Makes `account` pay for the C work of scripts from now on.
  void set_work_account(WorkAccount account) { account_ = std::move(account); }
  /// Charges `steps` of C work done for the running script: collected, and
  /// passed on (to the account, or to the instruction and time budgets) once
  /// they make a quantum, so that a small call costs only an addition. May
  /// raise a Lua error.
  void charge_work(lua_State* L, std::uint64_t steps);

  /// The host that owns `L` (any thread of it), or nullptr.
  static LuaHost* from(lua_State* L);

  /// Calls the function below its `nargs` arguments, protected, with a
  /// traceback handler. On success the results replace function and arguments;
  /// on failure the stack is as before the function was pushed, and an
  /// InputError located by the attribution rules below is thrown
  /// (`fallback` when nothing better is known).
  void call(int nargs, int nresults, const ErrorLocation& fallback = {});

  // --- source attribution ------------------------------------------------------
  // An object or an error belongs to the scene statement that caused it, not to
  // the kit function several frames down that carried it out. Files of mods the
  // scene uses are "library" files; the innermost frame outside them is the
  // user's line.

  /// Marks a loaded file (by display name) as belonging to a library mod.
  void mark_library(const std::string& display) { library_.insert(display); }
  bool is_library(std::string_view display) const {
    return library_.count(std::string(display)) > 0;
  }
  /// Display names of every file loaded so far.
  const std::set<std::string>& files() const { return files_; }
  /// The innermost Lua frame on the current stack that is not library code
  /// (falls back to the innermost Lua frame); empty if no Lua frame is running.
  ErrorLocation user_location(lua_State* L) const;

 private:
  struct Failure {
    ErrorLocation where;
    std::string message;
    std::string traceback;  ///< only for runtime errors, not for validation errors
  };
  static int on_error(lua_State* L);                  // the message handler of call()
  static void on_count(lua_State* L, lua_Debug* ar);  // the instruction budget
  [[noreturn]] void fail_too_long(lua_State* L);  // raises, and fails at every instruction after
  void check_deadline(lua_State* L);
  void describe_failure(lua_State* L);
  /// The known file whose (possibly truncated) chunk id is `src`.
  std::optional<std::string> file_for_chunk_id(std::string_view src) const;

  std::unique_ptr<MemoryBudget> budget_;
  std::size_t memory_limit_ = 0;
  std::uint64_t instruction_limit_ = 0;
  std::uint64_t instructions_ = 0;  // run by the outermost call(), in steps of kCountStep
  double seconds_limit_ = 0;
  std::chrono::steady_clock::time_point deadline_;
  PatternBudget patterns_;  // the pattern functions of this state point here
  WorkAccount account_;
  std::uint64_t work_pending_ = 0;  // C work charged but not yet passed on
  int depth_ = 0;                   // nested call()s (a manifest read while a scene runs)
  lua_State* L_ = nullptr;
  int handler_ref_ = -2;  // registry ref of the error handler (on_error), made once
  int ticks_ref_ = -2;    // registry ref of the tick function, when budget ticks are on
  std::set<std::string> files_;
  std::set<std::string> library_;
  std::optional<Failure> failure_;
};

/// Splits "chunk:12: message" into its parts; nullopt if there is no such prefix.
struct LocatedMessage {
  std::string chunk;
  int line = 0;
  std::string message;
};
std::optional<LocatedMessage> split_location(std::string_view message);

}  // namespace alloy::lua
