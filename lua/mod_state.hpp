// One loaded mod at run time: its own Lua state (so its own memory budget,
// and nothing shared with another mod but plain data through the world),
// the host prelude in that state, the budget of ticks and time per step, the
// mod's state table (which outlives reloads), and its current Program: the
// property types, stages and event handlers one run of its runtime file
// defined.
//
// Loading is a transaction (Defold's ResScriptRecreate): load_program() runs
// the mod's files in a fresh environment of the same state and collects what
// they define, touching nothing else; the caller validates the Program, and
// only then swaps it in (set_program) or throws it away. A failed attempt
// leaves the running Program, its functions and the state table untouched.
//
// Internal to lua/: apps use ModRuntime (mod_runtime.hpp).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lua/lua_host.hpp"
#include "lua/mod_loader.hpp"
#include "lua/stage_abi.hpp"
#include "lua/state_codec.hpp"
#include "runtime/interaction_function.hpp"
#include "runtime/stage.hpp"

namespace alloy::lua {

class LuaStage;

/// What a mod may spend. The tick budget counts loop iterations and function
/// calls of the mod's code (budget_ticks.hpp): deterministic, the same on
/// every machine. The time budget is a wall-clock backstop for what ticks do
/// not see (a long string operation in a library function).
struct ModBudget {
  std::size_t memory_bytes = 32u << 20;       ///< the mod's Lua state, all included
  std::uint64_t ticks_per_step = 20'000'000;  ///< over all its stages and handlers in one step
  double seconds_per_step = 0.25;             ///< same, wall clock
  std::uint64_t ticks_to_load = 200'000'000;  ///< running its files and on_load / on_reload
  double seconds_to_load = 5;

  // What the mod makes the host do besides running its code. Each printed
  // byte, emitted event and queued command costs host memory outside the
  // mod's Lua state, and printed text and events end in a terminal or a file:
  // none of it is seen by the memory budget above, so each has its own.
  // Loading (its files, on_load, on_reload) is counted as one step of its
  // own; a run lasts from a load or reload to the next. The defaults are far
  // above what the bundled mods do (a few lines and events per run, tens of
  // commands per step) and far below what fills a disk or the host's memory.
  // Past any of them the excess is dropped and the mod is stopped, as for
  // ticks and memory.
  std::size_t print_bytes_per_step = 64u
                                     << 10;  ///< text print() writes, tabs and newlines included
  std::size_t print_bytes_per_run = 4u << 20;
  std::uint64_t events_per_step = 1000;  ///< events w:emit publishes
  std::uint64_t events_per_run = 100'000;
  std::size_t event_bytes_per_step = 256u << 10;  ///< their type, text and value names
  std::size_t event_bytes_per_run = 16u << 20;
  /// Interaction-function calls queued (records written in place, or calls
  /// queued for the target), over all of the mod's interactions in one step.
  /// Commands are performed and freed at the target's next advance, so
  /// nothing accumulates over a run: the budget is per step only.
  std::uint64_t commands_per_step = 250'000;
  std::size_t command_bytes_per_step = 16u << 20;  ///< host memory those commands take
  /// Energy reports (w:energy, docs/modding.md "Energy"), over all of the
  /// mod's stages in one step: a mod books a few accounts a step.
  std::uint64_t energy_reports_per_step = 10'000;
  /// Accounts one stage of the mod may keep in the books (each a line of
  /// the ledger's table, and host memory for as long as the stage lives).
  std::size_t energy_accounts_per_stage = 32;
  /// The largest energy one report may carry, J: far above what a kit scene
  /// moves (joules over a run), far below where a sum of reports loses the
  /// other stages' figures in its rounding.
  double energy_joules = 1e9;
  /// Bytes of one error message (text, object, file) the host keeps and
  /// passes on; the rest is cut with a note of how much.
  std::size_t error_bytes = 4096;
  /// Instrument the mod's code with budget ticks. Without them nothing stops
  /// a runaway loop: only for trusted code, and to measure what they cost
  /// (bench/lua_stage.cpp).
  bool ticks = true;
  /// The mod's `state` table as snapshots and saves hold it (state_codec.hpp,
  /// docs/modding.md "Mod state and migrations"): its encoded bytes, its
  /// entries (keys, over all its tables) and how deeply its tables nest (the
  /// state itself is 1). A snapshot of a state past one is refused, naming
  /// the mod and the key; so is a saved state past one when restored.
  std::size_t state_bytes = 16u << 20;
  std::size_t state_entries = 1'000'000;
  std::size_t state_depth = 64;
};

/// An output column of a Lua derived set (number or vec3 per object).
struct OutputDecl {
  std::string name;
  PropertyKind kind = PropertyKind::Number;
  friend bool operator==(const OutputDecl&, const OutputDecl&) = default;
};

/// A stage a mod defined: what it declares, and where its functions are.
struct StageDecl {
  StageInfo info;
  std::vector<FunctionDecl> functions;  ///< a resolver's interaction functions
  std::vector<OutputDecl> provides;     ///< a derived set's outputs
  std::vector<std::string> settings;    ///< setting keys it accepts (defaults in its table)
  int def_ref = -2;                     ///< registry ref of the mod's table (functions, settings)
  ErrorLocation where;                  ///< the line that defined it
  /// Same declarations: live instances can take the new functions as they are.
  bool same_shape(const StageDecl& o) const;
};

/// Everything one run of a mod's runtime file defined.
struct Program {
  std::vector<PropertyDef> properties;
  std::vector<ErrorLocation> property_where;  ///< the line that defined each of `properties`
  std::vector<StageDecl> stages;
  std::vector<std::pair<std::string, int>> handlers;  ///< event type ("*": all), function ref
  int on_load = -2, on_reload = -2, on_unload = -2;   ///< function refs, or -2
  int on_migrate = -2;             ///< on_migrate(old_version, state) -> state, or -2
  std::vector<std::string> files;  ///< display names of the files it ran
  /// The loader that ran them: `require` in the mod's functions goes on
  /// using its module cache for as long as the program runs.
  std::shared_ptr<ModLoader> loader;
  const StageDecl* stage(std::string_view name) const;
};

class ModState : public std::enable_shared_from_this<ModState> {
 public:
  using Log = std::function<void(const std::string& mod, const std::string& line)>;

  ModState(Manifest manifest, std::vector<std::filesystem::path> search_path, ModBudget budget,
           Log log);
  ~ModState();
  ModState(const ModState&) = delete;
  ModState& operator=(const ModState&) = delete;

  const std::string& name() const { return manifest_.name; }
  const Manifest& manifest() const { return manifest_; }
  void set_manifest(Manifest m) { manifest_ = std::move(m); }
  LuaHost& host() { return *host_; }
  lua_State* state() const { return host_->state(); }
  const ModBudget& budget() const { return budget_; }
  /// The runtime file, or "" if the mod has none.
  std::string runtime_file() const;

  // --- programs -------------------------------------------------------------------
  /// Runs the mod's runtime file in a fresh environment and returns what it
  /// defined. Throws InputError (file, line) and leaves the running program
  /// alone. The manifest is read again by the caller when it changed.
  std::unique_ptr<Program> load_program();
  /// Frees the Lua references a program holds.
  void release(Program& program);
  /// The running program (nullptr before the first successful load).
  const Program* program() const { return program_.get(); }
  /// Makes `p` the running program, rebinds every live stage whose
  /// declarations did not change, and returns the old one (to be released).
  std::unique_ptr<Program> set_program(std::unique_ptr<Program> p);
  /// Calls on_load / on_reload / on_unload of the running program with the
  /// state table, under the load budget. Throws InputError.
  void call_hook(int ref, const char* what);

  /// Pushes the mod's state table (the same table across reloads).
  void push_state();

  // --- the state table in snapshots (state_codec.hpp) -------------------------------
  StateLimits state_limits() const {
    return {budget_.state_bytes, budget_.state_entries, budget_.state_depth};
  }
  /// The state table, encoded. Throws InputError naming the mod and the key
  /// path of what cannot be saved.
  std::vector<std::byte> save_state();
  /// A new state table from `bytes`, saved by version `from` of the mod:
  /// checked, decoded and, when `from` is not the manifest's version, passed
  /// through the program's on_migrate(from, state) under the load budget (its
  /// result, or the table it changed, checked as a state). Returns the
  /// table's registry ref, for commit_state or drop_state. Throws InputError
  /// naming the mod; the current state, the program and the mod's stop flag
  /// are as they were. `migrated` tells whether on_migrate ran.
  int prepare_state(const std::vector<std::byte>& bytes, const std::string& from,
                    bool* migrated = nullptr);
  /// A new, empty state table given to on_load (a mod a snapshot did not
  /// hold starts as if just loaded). Same contract as prepare_state.
  int prepare_fresh_state();
  /// Makes the table `ref` the state (its live stages see it as w.state)
  /// and frees the old one.
  void commit_state(int ref);
  /// Frees a prepared table that will not be used.
  void drop_state(int ref);
  /// Lifts a budget stop before a reload, with a new, empty state table (the
  /// old one may be half-updated: the mod was stopped in the middle of its
  /// work) and a full collection. restop() puts the stop back if the reload
  /// fails.
  void resume();
  void restop();

  // --- calls into the mod ------------------------------------------------------------
  /// Opens a call of the mod's code in world step `step` (loading: no step).
  void begin_call(std::uint64_t step);
  void begin_loading();
  /// Closes it; accounts its ticks and time to the step.
  void end_call();
  /// Stopped for a budget (until reloaded): its stages and handlers are skipped.
  bool stopped() const { return stopped_; }
  const std::string& stop_reason() const { return stop_reason_; }
  /// Set when the stop has been published as an event (once), and when the
  /// runtime has reported it (once).
  bool stop_event_sent = false;
  bool stop_reported = false;

  /// A registry ref of the prelude's function `fn` (new_stage, bind, run).
  int prelude_ref(const char* fn) const;
  /// Runs phase `phase` of the stage whose prelude record is `record_ref`,
  /// within the mod's budget for step `step`. Returns false and fills
  /// `error` if the mod's code failed or the mod was stopped.
  bool run_stage(int record_ref, const char* phase, double dt, double time, std::uint64_t step,
                 const ErrorLocation& fallback, InputError* error);

  // --- live stages -----------------------------------------------------------------
  void attach(LuaStage* s) { stages_.push_back(s); }
  void detach(LuaStage* s);
  const std::vector<LuaStage*>& stages() const { return stages_; }

  void log(const std::string& line) const {
    if (log_) log_(manifest_.name, line);
  }

  // --- what the mod makes the host do (ModBudget: print, events, commands) ----------
  /// What the mod made the host do in one step or one run.
  struct Output {
    std::uint64_t print_bytes = 0;    ///< printed text kept (newlines included)
    std::uint64_t print_dropped = 0;  ///< printed text dropped for a budget
    std::uint64_t events = 0;         ///< events accepted
    std::uint64_t event_bytes = 0;
    std::uint64_t commands = 0;  ///< interaction-function calls queued
    std::uint64_t command_bytes = 0;
    std::uint64_t energy_reports = 0;  ///< w:energy calls accepted
  };
  /// Counts one event of `bytes` (type, text, value names) the mod's code
  /// asks to emit in the current call. Returns "" if it fits; else the event
  /// is refused, the mod is stopped, and the reason is returned.
  std::string count_event(std::size_t bytes);
  /// Counts one energy report (w:energy) of the current call: "" if it fits
  /// the step's budget; else the mod is stopped and the reason returned.
  std::string count_energy_report();
  /// Asked before one of the mod's command queues grows to hold
  /// `bytes_in_call` bytes (`commands_in_call` commands, or as many as are
  /// known) in the current call: "" if the step's commands stay within the
  /// budget; else the mod is stopped and the reason returned. Never touches
  /// the Lua state (called through the FFI).
  std::string may_queue(std::size_t bytes_in_call, std::uint64_t commands_in_call);
  /// Counts the `n` commands of `bytes` that a call queued, before they are
  /// performed; "" if they fit, else (stopped) why.
  std::string count_commands(std::uint64_t n, std::size_t bytes);
  /// An error the mod raised, with its text, object and file cut to the
  /// budget's error_bytes (a mod can raise a string as large as its memory).
  InputError bounded(const InputError& e) const;
  /// Gives a stop decided where no Lua frame was known (an FFI call) the
  /// location of the error that unwound the mod's code.
  void place_stop(const ErrorLocation& where);
  const Output& output_this_run() const { return run_out_; }
  const Output& output_this_step() const { return step_out_; }

  /// Bytes the mod's Lua state holds.
  std::size_t memory_used() const { return host_->memory().used(); }
  /// Ticks the mod ran in its last step with a call (for tests and profiles).
  std::uint64_t ticks_last_step() const { return step_ticks_; }

 private:
  void make_state();
  void install_environment(lua_State* L, int env, const std::string& mod, int box_ref,
                           struct Collector* c);
  static int over_budget(lua_State* L);
  static int print_fn(lua_State* L);
  [[noreturn]] void stop(lua_State* L, const std::string& why);
  // Calls hook `fn` with (`from`, state `state_ref`) or (state `state_ref`)
  // under the load budget; a failure or a budget stop is an InputError that
  // leaves the mod as it was (not stopped). Leaves the hook's result pushed.
  void call_state_hook(int fn, const char* what, int state_ref, const std::string* from);
  // Stops the mod without raising (the caller refuses what it was asked and
  // the error unwinds the mod's code); place_stop adds the location later.
  void mark_stopped(const std::string& why);
  // A budget of ModBudget over: "its print ... (print_bytes_per_step)".
  std::string over(const char* what, std::uint64_t limit, const char* name, bool per_run,
                   const char* unit = "") const;  // unit "": bytes
  void charge();  // moves spent ticks from the counter to the step's total
  /// Stops the mod if its allocator refused since the call began, even when
  /// a pcall caught the error; raises only if `L` is given (from a tick).
  void stop_if_refused(lua_State* L);

  Manifest manifest_;
  std::vector<std::filesystem::path> search_path_;
  ModBudget budget_;
  Log log_;
  std::unique_ptr<LuaHost> host_;
  abi::Budget* abi_budget_ = nullptr;  // userdata in the state (the ticks read it)
  int budget_ud_ref_ = -2;
  int prelude_ref_ = -2;
  mutable std::vector<std::pair<std::string, int>> prelude_fns_;  // refs of its entry points
  int run_ref_ = -2;  // prelude_ref("run"), looked up at every call
  // The phase names run_stage passed ("apply", ...: string literals), as refs
  // to their Lua strings: a call pushes one without hashing it again.
  std::vector<std::pair<const char*, int>> phases_;
  int state_ref_ = -2;
  std::unique_ptr<Program> program_;
  std::vector<LuaStage*> stages_;

  // Budget accounting.
  bool loading_ = false;
  bool stopped_ = false;
  std::string stop_reason_;                   // with where it was
  std::string stop_message_;                  // without
  std::string saved_reason_, saved_message_;  // of a stop lifted for a reload
  std::uint64_t step_ = ~0ull;
  std::uint64_t step_ticks_ = 0;
  double step_seconds_ = 0;
  std::int32_t granted_ = 0;
  std::size_t refusals_seen_ = 0;  // allocator refusals when the call began
  std::uint64_t tick_limit_ = 0;
  std::chrono::steady_clock::time_point call_start_, deadline_;
  Output step_out_, run_out_;   // step_out_ belongs to step_
  bool stop_unplaced_ = false;  // stop_reason_ still lacks the mod's line
};

/// Where the print() of a script that is not a mod's runtime (a scene) goes,
/// and how much it may write.
struct PrintSink {
  std::function<void(const std::string& line)> write;
  std::uint64_t limit = 4u << 20;  ///< bytes, newlines included
  std::uint64_t used = 0;
  std::string who = "the scene";  ///< for the error: "the scene printed more than ..."
};
/// Sets print in the environment at `env` to one that writes to `sink`
/// (which must outlive the state). Past the limit, what fits is written, then
/// "... (N more bytes dropped)", and the script fails with an error.
void install_print(lua_State* L, int env, PrintSink* sink);

/// The stage definitions of `ModState::load_program` are parsed here; the
/// error names the line of the definition.
struct Collector;

}  // namespace alloy::lua
