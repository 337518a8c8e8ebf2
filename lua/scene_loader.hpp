// Loading a scene: the one entry point apps/ uses. A scene is a Lua file (or a
// mod folder whose mod.lua names its scene) that describes a world:
//
//   local kit = require "kit"
//   world { dt = 1/240, seconds = 5, settings = { ["gravity.uniform"] = { g = {0, -9.81, 0} } } }
//   kit.floor { name = "floor", at = {0, 0}, size = {4, 0.1} }
//   kit.bar   { name = "arm", material = "steel", at = {1, 2}, length = 1, width = 0.05 }
//   kit.hinge { name = "pivot", a = "arm", anchor = {0.5, 2} }
//   object    { name = "raw", position = {0, 1, 0}, shape = "sphere", radius = 0.1, mass = 1 }
//
// The scene's Lua runs in a sandbox and only records what it asks for (with
// the line of each statement); C++ then builds the WorldDef and the World and
// applies the objects. Any problem is an InputError that names the file, the
// line and the object; nothing reaches a resolver unchecked.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lua/mod_runtime.hpp"
#include "runtime/error.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

struct LoadOptions {
  /// Folders searched for mods by name, before the defaults: the folder that
  /// holds the scene's own mod, a `mods/` folder beside the scene, and the
  /// source tree's mods/.
  std::vector<std::filesystem::path> mod_paths;
  /// Bytes the scene's Lua may hold; 0 = no limit.
  std::size_t memory_limit = 64u << 20;
  /// Lua instructions the scene (with the mods it requires) may run while
  /// loading; 0 = no limit. Stops an endless loop in a scene.
  std::uint64_t instruction_limit = 2'000'000'000;
  /// Wall-clock seconds the scene's Lua may run while loading; 0 = no limit.
  double seconds_limit = 20;
  /// Steps one pattern call of the scene may take (lua_patterns.hpp).
  std::uint64_t pattern_steps = 10'000'000;
  /// Budgets of each mod with a runtime file the scene uses (its stages run
  /// in the world; mod_runtime.hpp).
  ModBudget mod_budget;
  /// Where those mods' print() and reports go (default: stderr).
  std::function<void(const std::string& mod, const std::string& line)> mod_log;
};

struct LoadedScene {
  std::string name;            ///< world{ name }, else the mod's name, else the file's stem
  std::filesystem::path file;  ///< the scene file that ran
  WorldDef def;
  /// The mods with Lua stages the scene uses (its own, the ones it requires
  /// and their dependencies), loaded and attached to `world`; null if none.
  /// Declared before `world`, which must go first.
  std::shared_ptr<ModRuntime> mods;
  std::unique_ptr<World> world;  ///< objects applied, not started
  double seconds = 0;            ///< suggested run length, 0 = none
  std::string description;
  /// world{ report = {...} }: values the CLI reports as the run goes, each
  /// "object.property[.component][@seconds]" (checked by the CLI).
  std::vector<std::string> report;
  /// Where each named object was defined (to locate errors found later).
  std::map<std::string, ErrorLocation, std::less<>> sources;
};

/// Runs a scene (a .lua file, or a mod folder whose manifest names its scene)
/// and builds its world. Throws InputError naming the file, the line and the object.
LoadedScene load_scene(const std::filesystem::path& path, PluginRegistry& registry,
                       const LoadOptions& options = {});

/// `alloy check`: loads a scene or a mod folder, builds the world and starts it
/// (instantiating the plugins it needs, which check their settings), without
/// stepping. A mod folder without a scene is checked by loading its main file.
/// Throws InputError.
void check(const std::filesystem::path& path, PluginRegistry& registry,
           const LoadOptions& options = {});

/// An error found after loading (a resolver refusing an object) with the
/// file and line of the object it names filled in from the scene.
InputError locate(const LoadedScene& scene, const InputError& error);

}  // namespace alloy::lua
