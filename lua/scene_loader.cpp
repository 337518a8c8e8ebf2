#include "lua/scene_loader.hpp"

#include <algorithm>
#include <cstdio>
#include <lua.hpp>
#include <optional>

#include "lua/alloy_api.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/mod_loader.hpp"
#include "lua/scene_bindings.hpp"
#include "lua/scene_builder.hpp"

#ifndef ALLOY_MODS_DIR
#define ALLOY_MODS_DIR "mods"
#endif

namespace alloy::lua {

namespace fs = std::filesystem;

namespace {

/// The file to run and the mod it belongs to (if any).
struct SceneSource {
  fs::path file;
  std::string display;
  std::optional<Manifest> mod;
};

struct RecordedScene {
  SceneSource source;
  SceneRecord record;
  std::vector<fs::path> search;  ///< the mod path the scene ran with
  std::vector<Manifest> mods;    ///< mods it used: required ones in order, then its own
};

SceneSource resolve(LuaHost& host, const fs::path& path, bool allow_library_mod) {
  const std::string display = display_path(path);
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw InputError(ErrorLocation{display, 0, ""}, "no such scene file or mod folder");
  SceneSource src;
  if (fs::is_directory(path, ec)) {
    Manifest m = read_manifest(host, path);
    fs::path file;
    if (!m.scene.empty()) {
      file = path / m.scene;
      if (!fs::is_regular_file(file, ec))
        throw InputError(ErrorLocation{m.file, 0, ""}, "mod '" + m.name + "' names its scene '" +
                                                           m.scene + "', but there is no file " +
                                                           display_path(file));
    } else if (allow_library_mod) {
      file = path / m.main;  // checking a library mod: run its main file
    } else {
      throw InputError(
          ErrorLocation{m.file, 0, ""},
          "mod '" + m.name + "' has no scene (add scene = \"scene.lua\" to its mod.lua)");
    }
    src.file = file;
    src.mod = std::move(m);
  } else {
    if (path.extension() != ".lua")
      throw InputError(ErrorLocation{display, 0, ""}, "a scene is a .lua file or a mod folder");
    src.file = path;
    fs::path folder = path.parent_path();
    if (folder.empty()) folder = ".";
    if (fs::is_regular_file(folder / "mod.lua", ec)) src.mod = read_manifest(host, folder);
  }
  src.display = display_path(src.file);
  return src;
}

/// Explicit folders first, then the defaults; each folder once.
std::vector<fs::path> search_path(const LoadOptions& options, const SceneSource& src) {
  std::vector<fs::path> candidates = options.mod_paths;
  if (src.mod) {
    fs::path parent = src.mod->folder.lexically_normal();
    if (parent.filename().empty()) parent = parent.parent_path();
    parent = parent.parent_path();
    candidates.push_back(parent.empty() ? fs::path(".") : parent);
  }
  fs::path beside = src.file.parent_path();
  candidates.push_back((beside.empty() ? fs::path(".") : beside) / "mods");
  candidates.push_back(ALLOY_MODS_DIR);

  std::vector<fs::path> out;
  std::vector<fs::path> seen;
  for (const auto& c : candidates) {
    std::error_code ec;
    if (!fs::is_directory(c, ec)) continue;
    const fs::path canonical = fs::weakly_canonical(c, ec);
    if (std::find(seen.begin(), seen.end(), canonical) != seen.end()) continue;
    seen.push_back(canonical);
    out.push_back(c);
  }
  return out;
}

RecordedScene run_scene(const fs::path& path, const LoadOptions& options, bool allow_library_mod) {
  // A scene is untrusted code too: instructions (pattern matching included),
  // memory, wall-clock time and the C stack are all bounded (lua_host.hpp).
  LuaHost host(HostOptions{options.memory_limit, options.instruction_limit, options.seconds_limit,
                           options.pattern_steps});
  RecordedScene out;
  out.source = resolve(host, path, allow_library_mod);
  const SceneSource& src = out.source;

  SceneRecorder recorder(host);
  // The scene's print() is bounded like a mod's (mod_state.hpp): its lines go
  // to the mods' log, at most the mods' print budget of a run.
  PrintSink print{[&](const std::string& line) {
                    if (options.mod_log)
                      options.mod_log(src.mod ? src.mod->name : "scene", line);
                    else
                      std::fprintf(stderr, "[%s] %s\n", src.mod ? src.mod->name.c_str() : "scene",
                                   line.c_str());
                  },
                  options.mod_budget.print_bytes_per_run};
  ModLoader mods(host, search_path(options, src), [&](lua_State* L, int env, const std::string&) {
    recorder.install(L, env);
    push_alloy_api(L);
    lua_setfield(L, env, "alloy");
    install_print(L, env, &print);
  });
  mods.set_scene_mod(src.mod);
  mods.add_scene_file(src.display);

  lua_State* L = host.state();
  StackGuard guard(L);
  host.load_file(src.file, src.display);
  mods.push_environment(src.mod ? src.mod->name : "");
  lua_setfenv(L, -2);
  host.call(0, 0, ErrorLocation{src.display, 0, ""});
  out.record = std::move(recorder.record());
  out.search = mods.search_path();
  for (const auto& name : mods.required_mods())
    if (const Manifest* m = mods.find(name)) out.mods.push_back(*m);
  if (src.mod) out.mods.push_back(*src.mod);
  return out;
}

/// Loads the runtime files of the mods the scene used, so that their property
/// types and plugins are registered before the world is built. Null if none
/// of them has one.
std::shared_ptr<ModRuntime> start_mods(const RecordedScene& rec, PluginRegistry& registry,
                                       const LoadOptions& options) {
  ModRuntimeOptions o{rec.search, options.mod_budget, options.mod_log};
  for (const auto& [mod, properties] : rec.record.world.grants)
    o.grants.push_back({mod, properties, rec.record.world.where});
  auto runtime = std::make_shared<ModRuntime>(registry, std::move(o));
  for (const Manifest& m : rec.mods) runtime->load(m);
  for (const auto& [mod, properties] : rec.record.world.grants)
    if (!runtime->has(mod))
      throw InputError(rec.record.world.where,
                       "world: 'grants' names mod '" + mod +
                           "', which this scene does not run (a mod with a runtime file that "
                           "the scene requires, or whose scene it is)");
  if (runtime->loaded().empty()) return nullptr;
  return runtime;
}

}  // namespace

LoadedScene load_scene(const fs::path& path, PluginRegistry& registry, const LoadOptions& options) {
  RecordedScene rec = run_scene(path, options, false);
  std::shared_ptr<ModRuntime> mods = start_mods(rec, registry, options);
  BuiltScene built = build_scene(rec.record, registry);
  if (mods) mods->attach(*built.world);
  const RecordedWorld& w = rec.record.world;
  LoadedScene scene;
  scene.mods = std::move(mods);
  scene.name = !w.name.empty()  ? w.name
               : rec.source.mod ? rec.source.mod->name
                                : rec.source.file.stem().string();
  scene.file = rec.source.file;
  scene.def = std::move(built.def);
  scene.world = std::move(built.world);
  scene.seconds = w.seconds;
  scene.report = w.report;
  scene.description = !w.description.empty() ? w.description
                      : rec.source.mod       ? rec.source.mod->description
                                             : "";
  scene.sources = std::move(built.sources);
  return scene;
}

void check(const fs::path& path, PluginRegistry& registry, const LoadOptions& options) {
  RecordedScene rec = run_scene(path, options, true);
  std::shared_ptr<ModRuntime> mods = start_mods(rec, registry, options);  // checks their stages too
  BuiltScene built = build_scene(rec.record, registry);
  if (mods) mods->attach(*built.world);
  LoadedScene scene;
  scene.file = rec.source.file;
  scene.sources = std::move(built.sources);
  try {
    built.world->start();  // the plugins the scene needs are created and check their settings
  } catch (const InputError& e) {
    throw locate(scene, e);
  }
}

InputError locate(const LoadedScene& scene, const InputError& error) {
  if (!error.where().file.empty()) return error;
  ErrorLocation where = error.where();
  if (auto it = scene.sources.find(where.object);
      !where.object.empty() && it != scene.sources.end()) {
    where.file = it->second.file;
    where.line = it->second.line;
  } else {
    where.file = display_path(scene.file);
  }
  return InputError(where, error.bare());
}

}  // namespace alloy::lua
