// Mods: folders with a manifest (mod.lua) and Lua files, found by name on a
// search path, loaded by the sandbox's `require`.
//
//   mods/kit/mod.lua       return { name = "kit", version = "0.1.0", depends = {},
//                                   description = "...", main = "init.lua" }
//   require "kit"          runs mods/kit/init.lua (the manifest's `main`)
//   require "kit.materials"  runs mods/kit/materials.lua
//
// Only Lua source files inside a mod folder can be required: names are
// dot-separated identifiers, so no path can leave the folder, and there is no
// native-code loader, and no file outside the mod's folder (a symlink or `..`
// out of it is refused: contained_file). Each mod runs in its own sandbox
// environment (its files share it); the scene's own mod shares the scene's. A
// module runs once per load; later requires get its cached value. A mod that
// requires another must list it in `depends`. Cycles are reported with the
// chain.
//
// Who requires is known for certain: each environment's `require` carries the
// name of its mod (a script cannot pose as another mod by where it calls
// from). Another mod's module is handed over read-only (alloy.freeze, shallow),
// and a module may return alloy.per_mod(f) to give each requiring mod its own
// value f(name) ("" for a loose scene), made once: the kit gives each mod a
// kit whose definitions are owned by that mod, and keeps its inner modules to
// itself (f returns nil: "keeps this module to itself").
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/error.hpp"

struct lua_State;

namespace alloy::lua {

class LuaHost;

struct Manifest {
  std::string name;
  std::string version;
  std::string description;
  std::vector<std::string> depends;
  std::string scene;              ///< scene file of the mod, relative to its folder ("" = none)
  std::string main = "init.lua";  ///< the file `require "<name>"` runs
  /// The file that defines the mod's property types, stages and event
  /// handlers, run by the world's ModRuntime in the mod's own Lua state
  /// ("" = none: the mod only has parts and scenes).
  std::string runtime;
  std::filesystem::path folder;
  std::string file;  ///< display name of mod.lua, for messages
};

/// Reads and checks folder/mod.lua. The manifest is data: it runs in an empty
/// environment of a small host of its own (tight memory, instruction, time and
/// pattern limits), not in `host`, which is kept for the callers' sake.
/// Throws InputError at the manifest.
Manifest read_manifest(LuaHost& host, const std::filesystem::path& folder);

/// Lexically normal display form of a path ("mods/kit/init.lua").
std::string display_path(const std::filesystem::path& p);

/// The file `file` of mod `mod` (whose folder is `folder`) as it really is on
/// disk: every symlink and `..` resolved. A mod's files stay inside its
/// folder: if `file` resolves to a place outside it (a symlink to /etc/passwd
/// or into another mod, a `..`), throws InputError at `where` naming the mod
/// and the file. A file that does not exist is returned as it is (the caller
/// reports it missing). Used for mod.lua, every file a manifest names, and
/// every file `require` runs.
std::filesystem::path contained_file(const std::string& mod, const std::filesystem::path& folder,
                                     const std::filesystem::path& file,
                                     const ErrorLocation& where = {});

class ModLoader {
 public:
  /// Called for each new environment (at the given index) of mod `mod` ("" for
  /// the scene's) to add the host API.
  using Decorate = std::function<void(lua_State*, int env, const std::string& mod)>;

  ModLoader(LuaHost& host, std::vector<std::filesystem::path> search_path, Decorate decorate);
  /// Frees the loader's environments and module cache (the modules stay alive
  /// as long as something else refers to them). A `require` kept by a script
  /// fails cleanly afterwards.
  ~ModLoader();
  /// Replaces the decoration of environments made from now on.
  void set_decorate(Decorate decorate) { decorate_ = std::move(decorate); }
  ModLoader(const ModLoader&) = delete;
  ModLoader& operator=(const ModLoader&) = delete;

  /// The mod the scene belongs to (nullopt: a loose scene file). Its files share
  /// the scene's environment and count as the user's code, not library code.
  void set_scene_mod(std::optional<Manifest> manifest);
  /// Registers a file run in the scene's environment (the scene itself).
  void add_scene_file(const std::string& display);

  /// Pushes the environment of `mod` (the scene's when `mod` is the scene mod
  /// or ""), creating it on first use.
  void push_environment(const std::string& mod);

  const std::vector<std::filesystem::path>& search_path() const { return search_path_; }
  /// The manifest of the mod called `name` on the search path, or nullptr.
  const Manifest* find(const std::string& name);
  /// Names of every mod on the search path (for "did you mean").
  std::vector<std::string> available() const;
  /// Display names of the files this loader ran, with the mod of each ("" for
  /// the scene's own), in no particular order.
  const std::map<std::string, std::string>& loaded_files() const { return file_mod_; }
  /// Names of the mods whose files this loader ran (the scene's own excluded),
  /// in the order they were first required.
  const std::vector<std::string>& required_mods() const { return required_; }

 private:
  static int require_fn(lua_State* L);
  int require(lua_State* L);
  /// Replaces the module value on the stack top by what `requirer` gets of
  /// module `name` of mod `mod`: a per_mod view, or a read-only view for
  /// another mod (cached per requirer).
  int deliver(lua_State* L, const std::string& name, const std::string& mod,
              const std::string& requirer);
  std::string scene_mod_name() const { return scene_mod_ ? scene_mod_->name : ""; }
  /// "file:line: " of the library mod's file that called require (a refusal
  /// names it: the host would put the error on the scene line that required
  /// the library), or "" for the scene's own code.
  std::string library_caller(lua_State* L) const;
  void check_depends(const Manifest& m);

  LuaHost& host_;
  std::vector<std::filesystem::path> search_path_;
  Decorate decorate_;
  std::optional<Manifest> scene_mod_;
  std::map<std::string, std::optional<Manifest>> manifests_;  // by name; nullopt = not found
  std::map<std::string, std::string> file_mod_;               // display name -> mod ("" = scene)
  std::vector<std::string> loading_;                          // require chain, for cycles
  std::vector<std::string> checked_;                          // mods whose depends exist
  std::vector<std::string> required_;                         // mods run, in first-require order
  ModLoader** box_ =
      nullptr;  // userdata holding `this`, the upvalue of require; nulled at destruction
  int box_ref_ = -2;
  int envs_ref_ = -2;    // registry ref: mod name -> environment (this loader's own)
  int loaded_ref_ = -2;  // registry ref: module name -> value (this loader's own)
  int views_ref_ = -2;   // registry ref: "module|requirer" -> the value that mod gets
};

}  // namespace alloy::lua
