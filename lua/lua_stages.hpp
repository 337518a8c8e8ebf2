// Lua stages: a resolver, a derived set or an interaction written in a mod,
// as an ordinary plugin stage of the world. The world schedules, primes,
// skips and scopes them exactly like native stages (they are created by a
// PluginDef's factory and see only WorldView / ResolverAccess); only their
// body is Lua, called once per phase with whole columns, never per object.
//
// The contract, as for native stages (runtime/stage.hpp):
//   resolver     advance(w, dt) reads what it declared, writes only its
//                declared `writes` (through ColumnWriter: version bumps,
//                scope and bounds checked), and performs its queued commands
//                (w:commands): the interaction functions other stages called
//                in the previous interact phase. build(w) after structure
//                changes. Commands are cleared after each advance.
//   derived set  update(w) recomputes its outputs (`provides`: a number or a
//                vec3 per object) from what it declared; outputs start empty
//                at each update; skipped when no input changed.
//   interaction  apply(w) reads anything it declared and queues commands on
//                its one `target` (w.target.add_force(i, f)), native or Lua.
//
// A Lua error disables the stage (with the mod's file, line and traceback,
// and a `stage_disabled` event); the world goes on. A mod over its budget is
// stopped as a whole (`mod_stopped`). A successful reload re-enables both.
#pragma once

#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "lua/mod_state.hpp"
#include "lua/stage_abi.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

class NativeTarget;
class LuaResolver;
class LuaDerivedSet;

/// The FFI entry points (stage_abi.hpp), shared by every stage.
const abi::Api& stage_api();
/// Pushes the table of host functions the prelude calls by name
/// (last_error, name, find, alive, emit, slow_get, slow_set).
void push_stage_host_functions(lua_State* L);

/// What the Lua side of every kind of stage shares.
class LuaStage {
 public:
  LuaStage(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx);
  virtual ~LuaStage();
  LuaStage(const LuaStage&) = delete;
  LuaStage& operator=(const LuaStage&) = delete;

  const std::string& name() const { return decl_name_; }
  ModState& mod() { return *mod_; }
  /// Disabled after a Lua error, until the mod is reloaded.
  bool disabled() const { return disabled_; }
  const std::string& disabled_reason() const { return reason_; }
  /// The mod was reloaded with the same declarations: take its new functions
  /// and run again if disabled.
  void rebind(const StageDecl& decl);

  /// The mod's state table was replaced (a stopped mod starting over).
  void reset_state();
  /// Set once the runtime has reported this stage's failure.
  bool reported = false;

  // --- the FFI entry points (stage_abi.hpp), and the host functions ------------
  static std::int32_t api_fetch(void* stage, std::int32_t column) noexcept;
  static std::int32_t api_set_scalar(void* stage, std::int32_t column, double slot,
                                     double v) noexcept;
  static std::int32_t api_set_vec3(void* stage, std::int32_t column, double slot, double x,
                                   double y, double z) noexcept;
  static std::int32_t api_set_quat(void* stage, std::int32_t column, double slot, double w,
                                   double x, double y, double z) noexcept;
  static std::int32_t api_has(void* stage, std::int32_t column, double slot) noexcept;
  static std::int32_t api_grow(void* stage) noexcept;
  static std::int32_t api_commands(void* stage, std::int32_t function) noexcept;
  static std::int32_t api_contacts(void* stage, std::int32_t which) noexcept;
  static std::int32_t api_bulk(void* stage, std::int32_t function, std::int32_t column) noexcept;
  static int host_last_error(lua_State* L);
  static int host_name(lua_State* L);
  static int host_find(lua_State* L);
  static int host_alive(lua_State* L);
  static int host_emit(lua_State* L);
  static int host_slow_get(lua_State* L);
  static int host_slow_set(lua_State* L);
  static int host_energy(lua_State* L);

  /// Hands what the stage's calls booked with w:energy since the last report
  /// to the ledger (runtime/energy_ledger.hpp): flows summed, stores at the
  /// level last reported. The overrides of Stage::report_energy call it.
  void report_books(EnergyReport& out);

 protected:
  /// Calls the stage's `phase` function. Returns false if it failed (the
  /// stage is then disabled, or its mod stopped, and an event says so).
  bool invoke(const WorldView& view, ResolverAccess* access, const char* phase, double dt);
  bool runnable() const { return !disabled_ && !mod_->stopped(); }
  /// Why this stage may not report a transfer named `account` ("" if it
  /// may): docs/modding.md "Energy".
  std::string transfer_refused(const std::string& account) const;

  /// Where a column's data comes from.
  struct Source {
    enum What : std::uint8_t { Property, Output, DerivedInput } what = Property;
    PropertyId property = kNoProperty;
    PropertyKind kind = PropertyKind::Number;
    bool writable = false;
    int output = -1;                     ///< index into the set's outputs
    const LuaDerivedSet* set = nullptr;  ///< DerivedInput: the Lua derived set read
  };
  /// Pushes the stage's settings: the mod's defaults, then the scene's values.
  void push_settings(const StageDecl& decl);
  /// Fills column `k`'s info for the current call.
  void fetch(std::size_t k);
  /// The object in `slot`, or false with last_error_ set.
  bool check_slot(double slot, std::uint32_t& out);
  std::int32_t error(std::string message) {
    last_error_ = std::move(message);
    return 1;
  }
  /// What an FFI entry point returns when a C++ exception stopped it: the
  /// message (prefix + what) as the last error, set without throwing (no
  /// exception may leave a function LuaJIT's FFI called). Returns 1.
  std::int32_t refuse(const char* what, const char* prefix = "") noexcept;
  /// The stage of a host function's first argument, which must be in a call.
  static LuaStage* stage_in_call(lua_State* L);
  /// The body of invoke(): opens the call, runs the mod's function and
  /// performs what it queued. Returns false with `failure` set if it failed.
  bool run_call(const WorldView& view, ResolverAccess* access, const char* phase, double dt,
                InputError& failure);
  /// Takes back everything lent to Lua for the call, on every path out of
  /// it (docs/architecture.md, "The Lua boundary").
  void end_call() noexcept;
  /// Performs the commands an interaction appended during its call (on its
  /// target's interaction functions). Returns false with last_error_ set if
  /// one is refused (an object that died).
  bool perform_commands();
  // Counts the commands of the call against the mod's budget; false (and why) if over.
  bool count_commands(InputError& failure);
  /// Performs the call's bulk buffers (add_force_each and the like), after
  /// its single commands. Returns false with last_error_ set if one is refused.
  bool perform_bulk();
  virtual void fill_outputs(std::size_t k, abi::Column& info) {}
  virtual std::int32_t commands(std::int32_t fn) { return error("only a resolver has commands"); }

  std::shared_ptr<ModState> mod_;
  std::string decl_name_;
  std::string instance_;  // with "@area" for a stage of an area
  std::string target_;    // an interaction's target
  StageKind kind_;
  ErrorLocation where_;
  World& world_;
  PluginSettings settings_;  // the scene's, for this stage
  std::vector<Source> sources_;
  /// Writers of the current resolver call, per column (made at fetch).
  using AnyWriter = std::variant<std::monostate, ColumnWriter<double>, ColumnWriter<std::int64_t>,
                                 ColumnWriter<std::uint8_t>, ColumnWriter<Vec3>, ColumnWriter<Quat>,
                                 ColumnWriter<EnumValue>, ColumnWriter<std::string>>;
  std::vector<AnyWriter> writers_;
  std::vector<std::string> column_names_;
  abi::Column* infos_ = nullptr;  // userdata in the mod's state, one per source
  abi::Call* call_ = nullptr;     // userdata in the mod's state
  int record_ref_ = -2;
  const WorldView* view_ = nullptr;   // during a call
  ResolverAccess* access_ = nullptr;  // during a resolver's call
  std::string last_error_;
  bool disabled_ = false;
  std::string reason_;

  // Target of an interaction: native (a binder) or another Lua resolver.
  std::unique_ptr<NativeTarget> native_target_;
  LuaResolver* lua_target_ = nullptr;
  std::vector<FunctionDecl> target_functions_;
  std::vector<double> commands_;  // the call's command buffer (abi::Call::buf)
  // A native target taking load records in place (abi::Call::loads): the
  // room opened for a call, the last call's count (the next call's room).
  bool in_place_ = false;
  std::size_t records_room_ = 16;
  // Per slot, the live object's packed id or 0 (abi::Call::ids), as of the
  // store's structure version `ids_version_`: rebuilt only when objects
  // were created or destroyed since.
  std::vector<std::uint64_t> ids_;
  std::uint64_t ids_version_ = ~0ull;
  void refresh_ids(const PropertyStore& store);
  // Bulk buffers (abi::Bulk): a few per call, their storage kept between calls.
  static constexpr int kMaxBulk = 8;
  struct BulkStore {
    std::vector<double> values;
    std::vector<std::uint8_t> present;
  };
  abi::Bulk* bulks_ = nullptr;  // userdata in the mod's state, kMaxBulk of them
  BulkStore bulk_store_[kMaxBulk];
  int bulk_used_ = 0;
  // The collisions derived set, if declared.
  const ContactSet* collisions_ = nullptr;
  // Contacts reach Lua with their impulses, which a stage may read: declared.
  ImpulseDemand impulses_;
  // The call's lists of contacts (began, ongoing, ended, touching), each made
  // at most once per call (bit k of contacts_made_), so that a list stays
  // where it is while the stage iterates over it and asks for another.
  static constexpr int kContactLists = 4;
  std::vector<abi::Contact> contacts_[kContactLists];
  std::uint32_t contacts_made_ = 0;
  // The books of w:energy: per account, the flow since the last report, or
  // a store's last level (EnergyReport's meaning).
  struct Booked {
    std::string account;
    EnergyKind kind;
    double joules = 0;
  };
  std::vector<Booked> booked_;
};

class LuaResolver final : public Resolver, public LuaStage {
 public:
  LuaResolver(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx);
  void report_energy(const WorldView&, EnergyReport& out) override { report_books(out); }
  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  /// Interaction functions, as declared.
  const std::vector<FunctionDecl>& functions() const { return functions_; }
  /// Appends a command (an interaction function called by another stage).
  /// `args` holds the packed arguments; throws nothing, returns an error text.
  std::string push(std::int32_t fn, std::uint32_t slot, const double* args, std::int32_t nargs);
  /// Commands waiting for the next advance (tests).
  std::size_t queued() const;

 private:
  std::int32_t commands(std::int32_t fn) override;
  std::vector<FunctionDecl> functions_;
  std::vector<std::vector<double>> queue_;  // per function: slot, args..., slot, args...
};

class LuaDerivedSet final : public DerivedSet, public LuaStage {
 public:
  LuaDerivedSet(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx);
  void report_energy(const WorldView&, EnergyReport& out) override { report_books(out); }
  void update(const WorldView& world) override;
  const std::vector<OutputDecl>& outputs() const { return outputs_; }
  /// The output column `k` as a reader sees it (valid until the next update).
  void describe(int k, abi::Column& info) const;

 private:
  void fill_outputs(std::size_t k, abi::Column& info) override;
  struct Output {
    std::vector<double> num;
    std::vector<Vec3> vec3;
    std::vector<std::uint8_t> present;
    std::vector<std::uint32_t> members;
  };
  std::vector<OutputDecl> outputs_;
  std::vector<Output> data_;
};

class LuaInteraction final : public Interaction, public LuaStage {
 public:
  LuaInteraction(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx);
  void report_energy(const WorldView&, EnergyReport& out) override { report_books(out); }
  void apply(const WorldView& world) override;
};

/// The factory a mod's PluginDef carries. It finds the stage's declarations
/// in the mod's running program when the world instantiates it.
struct LuaStageFactory {
  std::shared_ptr<ModState> mod;
  std::string stage;
  std::unique_ptr<Stage> operator()(PluginContext& ctx) const;
};

/// The PluginDef of a mod's stage.
PluginDef make_plugin(const std::shared_ptr<ModState>& mod, const StageDecl& decl);

/// Whether `def` was registered by `mod` (and not by someone else under the same name).
bool registered_by(const PluginDef& def, const ModState& mod);

}  // namespace alloy::lua
