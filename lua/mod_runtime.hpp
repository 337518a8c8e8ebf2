// The mods of a running world: what an app that runs a World uses to load
// mods with Lua stages, to hot-reload them while the world runs, and to
// unload them.
//
//   PluginRegistry registry;  register_native_plugins(registry);
//   lua::ModRuntime mods(registry, {.mod_paths = {"mods"}});
//   mods.load("magic");                 // property types and plugins registered
//   World world(registry);  ...  mods.attach(world);
//   mods.watch();                       // inotify, or polling where there is none
//   for (;;) { world.step(); for (auto& r : mods.poll()) log(r); }
//
// (load_scene does the loading and attaching for the mods a scene uses, and
// hands the runtime over in LoadedScene::mods.)
//
// Each mod runs in its own Lua state with its own memory budget, and a budget
// of ticks and time per step (mod_state.hpp). Its stages are ordinary plugins
// in the registry (lua_stages.hpp): areas, swaps, priming and skipping apply
// to them as to native ones.
//
// Reload is a transaction (Defold's ResScriptRecreate): the mod's files are
// run again in a fresh environment and what they define is checked against
// the registry; only if all is well is it swapped in. Objects keep every
// property, the mod keeps its state table, live stages take the new functions
// (stages whose declarations changed are re-created: built from properties
// and primed), and `mod.on_reload(state)` is called. If anything fails, the
// old code keeps running and the report says why, with file and line.
//
// Unload removes everything the mod registered: its plugins (and the world's
// stages of them, with the stages that depend on them), its event handlers,
// its Lua state. Property types stay registered: objects may still carry
// them, and a property type is a name and a kind, not behaviour; reloading the
// mod registers the same definitions again (a changed kind is refused).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lua/mod_state.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

class FileWatcher;

/// A scene's grant to a mod (world { grants = { wind = { "velocity" } } }):
/// the mod's resolvers may also write these properties, which belong to
/// others. Without one a Lua resolver writes only the properties its own mod
/// defines.
struct WriteGrant {
  std::string mod;                      ///< the mod granted
  std::vector<std::string> properties;  ///< what its resolvers may write besides its own
  ErrorLocation where;                  ///< the scene line that granted it
};

struct ModRuntimeOptions {
  /// Folders searched for mods by name.
  std::vector<std::filesystem::path> mod_paths;
  /// Each mod's budgets.
  ModBudget budget;
  /// Where a mod's print() and the runtime's reports go (default: stderr).
  std::function<void(const std::string& mod, const std::string& line)> log;
  /// watch() scans modification times instead of using inotify.
  bool poll_files = false;
  /// The scene's grants of others' properties to mods (none: each mod writes
  /// only its own).
  std::vector<WriteGrant> grants;
};

/// What happened to a mod: for the CLI, the viewer and tests.
struct ModReport {
  enum class Kind { Loaded, Reloaded, ReloadFailed, Unloaded, StageDisabled, Stopped, Note };
  Kind kind = Kind::Note;
  std::string mod;
  std::string message;  ///< complete on its own (file:line: ...)
  ErrorLocation where;  ///< of a failure
};

class ModRuntime {
 public:
  ModRuntime(PluginRegistry& registry, ModRuntimeOptions options = {});
  /// Unloads every mod (its plugins leave the registry). Worlds that use the
  /// mods' stages must be destroyed first.
  ~ModRuntime();
  ModRuntime(const ModRuntime&) = delete;
  ModRuntime& operator=(const ModRuntime&) = delete;

  /// Loads the mod `name` from the mod paths, after its dependencies (a mod
  /// without a runtime file loads as nothing). Loading a loaded mod does
  /// nothing. Throws InputError (file, line), registering nothing.
  void load(const std::string& name);
  /// Loads the mod in `folder` (its name is the folder's).
  void load_folder(const std::filesystem::path& folder);
  /// Loads a mod whose manifest was already read (by the scene loader).
  void load(const Manifest& manifest);

  /// The world whose stages the mods' plugins make: events and handlers go
  /// through it, and reloads tell it which plugins changed; its snapshots
  /// hold each mod's state table (save_states, prepare_states). One world.
  void attach(World& world);

  // --- the mods' state in snapshots (docs/modding.md, "Mod state and migrations") ----
  /// Adds each loaded mod's state table, encoded, to `out.mod_states`, in
  /// load order. Throws InputError naming the mod and the key path of a value
  /// a state may not hold (the snapshot is then not taken).
  void save_states(Snapshot& out);
  /// Reads `in.mod_states` for a restore: every mod it names must be loaded
  /// (else an InputError naming it); each state is checked and decoded, and a
  /// state saved by another version of its mod goes through the mod's
  /// on_migrate(old_version, state), once; a loaded mod the snapshot does not
  /// hold gets a new state and its on_load. Nothing changes until the
  /// returned commit is called (World::restore calls it when the world takes
  /// the snapshot); an error in any mod changes nothing in any.
  std::function<void()> prepare_states(const Snapshot& in);
  World* world() const { return world_; }

  /// Reloads `name` from disk as a transaction; never throws for the mod's
  /// errors (the report says). Between steps only.
  ModReport reload(const std::string& name);
  /// Unregisters everything the mod registered and closes its Lua state.
  /// Between steps only. Throws InputError if another loaded mod depends on it.
  void unload(const std::string& name);

  /// Starts watching the loaded mods' folders for changed files (inotify,
  /// else polling twice a second).
  void watch();
  bool watching() const { return watcher_ != nullptr; }
  /// Between steps: reloads the mods whose files changed since the last poll
  /// (when watching), and returns what happened since the last call,
  /// including stages disabled and mods stopped in the steps since.
  std::vector<ModReport> poll();

  // --- introspection -----------------------------------------------------------------
  /// Loaded mods, in load order.
  std::vector<std::string> loaded() const;
  bool has(const std::string& name) const { return find(name) != nullptr; }
  /// The plugins a mod registered, in registration order.
  std::vector<std::string> plugins_of(const std::string& name) const;
  /// The event handlers a mod registered.
  std::size_t handlers_of(const std::string& name) const;
  /// The files of a mod's program (what a reload runs again).
  std::vector<std::string> files_of(const std::string& name) const;
  /// Whether a mod is stopped for its budget, and why.
  bool stopped(const std::string& name) const;
  std::string stop_reason(const std::string& name) const;
  /// Bytes a mod's Lua state holds.
  std::size_t memory_of(const std::string& name) const;
  /// What a mod made the host do since it was last loaded: bytes printed,
  /// events emitted, commands queued (ModBudget bounds them).
  ModState::Output output_of(const std::string& name) const;
  PluginRegistry& registry() { return registry_; }

 private:
  struct Loaded;
  Loaded* find(const std::string& name) const;
  void load_manifest(const Manifest& manifest, std::vector<std::string>& chain);
  /// Checks `p` against the registry as `mod` would register it.
  void validate(const ModState& mod, const Program& p) const;
  /// The ownership rules of `validate`: a mod defines no property that is
  /// another's, and its resolvers write only its own properties and those the
  /// scene grants it. The refusal names both owners and the line.
  void check_ownership(const ModState& mod, const Program& p) const;
  /// Registers `p` for `mod`, replacing its current program, and tells the
  /// world which plugins changed.
  void commit(Loaded& l, std::unique_ptr<Program> p, bool first);
  void dispatch(const Event& e);
  /// Handler `h` of `l` raised `raised`, or its mod was stopped in it: the
  /// handler is disabled, or the stop told. Whether the mod's other handlers
  /// may still run.
  bool handler_failed(Loaded& l, std::size_t h, const InputError& raised);
  /// Holds a demand for contact impulses on the world's collisions set while a
  /// loaded mod handles contact_ended (or every event), whose impulse value
  /// exists only if someone asks (runtime/contact_set.hpp).
  void hold_impulses();
  void report(ModReport r);

  PluginRegistry& registry_;
  ModRuntimeOptions options_;
  std::vector<std::unique_ptr<Loaded>> mods_;
  World* world_ = nullptr;
  ImpulseDemand impulses_;
  const Stage* impulses_from_ = nullptr;  // the collisions stage impulses_ was asked of
  std::uint64_t impulses_checked_ = ~std::uint64_t(0);  // the step hold_impulses last looked at
  std::shared_ptr<ModRuntime*> self_;                   // the world's observer holds a weak_ptr
  std::unique_ptr<FileWatcher> watcher_;
  std::vector<ModReport> reports_;
};

}  // namespace alloy::lua
