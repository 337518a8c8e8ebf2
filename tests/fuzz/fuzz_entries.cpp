#include "tests/fuzz/fuzz_entries.hpp"

#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "lua/mod_runtime.hpp"
#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/save_file.hpp"
#include "runtime/world.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace alloy::fuzz {

namespace fs = std::filesystem;

namespace {

/// Budgets small enough that a hostile input is stopped well within the
/// fuzzer's timeout, large enough for the bundled scenes and mods.
lua::LoadOptions load_options() {
  lua::LoadOptions o;
  o.memory_limit = 32u << 20;
  o.instruction_limit = 20'000'000;
  o.mod_budget.memory_bytes = 16u << 20;
  o.mod_budget.ticks_per_step = 2'000'000;
  o.mod_budget.seconds_per_step = 0.5;
  o.mod_budget.ticks_to_load = 20'000'000;
  o.mod_budget.seconds_to_load = 2;
  o.mod_log = [](const std::string&, const std::string&) {};  // a mod's print() is not the finding
  return o;
}

/// Collects what happened to the mods (stages disabled, mods stopped), as the
/// CLI does between steps; printed with ALLOY_FUZZ_VERBOSE=1.
void poll(lua::ModRuntime* mods) {
  if (!mods) return;
  for (const lua::ModReport& r : mods->poll())
    if (verbose())
      std::fprintf(stderr, "alloy fuzz: mod %s: %s\n", r.mod.c_str(), r.message.c_str());
}

/// Starts the world and steps it, polling the mods' reports between steps as
/// the CLI's watch loop does.
void run_world(lua::LoadedScene& scene, int steps) {
  World& world = *scene.world;
  world.start();
  for (int i = 0; i < steps; ++i) {
    world.step();
    poll(scene.mods.get());
  }
}

// ---------------------------------------------------------------------------
// The mod target's input: files after "--- NAME" lines

struct ModFile {
  std::string name, text;
};

/// Whether `name` is a plain file name of a mod (letters, digits, '_', '.',
/// ending in .lua): nothing the split could turn into a path.
bool plain_lua_name(std::string_view name) {
  if (name.size() < 5 || name.size() > 40 || name.substr(name.size() - 4) != ".lua") return false;
  if (name[0] == '.') return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.')) return false;
  return true;
}

/// The folder the mod target writes to: the manifest's `name = "..."` when it
/// is a plain identifier (mods are found by folder name), else "fz".
std::string mod_folder_name(const std::string& manifest) {
  const std::size_t key = manifest.find("name = \"");
  if (key == std::string::npos) return "fz";
  const std::size_t start = key + 8, end = manifest.find('"', start);
  if (end == std::string::npos || end == start || end - start > 32) return "fz";
  for (std::size_t i = start; i < end; ++i) {
    const char c = manifest[i];
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return "fz";
  }
  return manifest.substr(start, end - start);
}

std::vector<ModFile> split_mod_files(std::string_view text) {
  std::vector<ModFile> files{{"mod.lua", ""}};
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    if (line.size() > 4 && line.substr(0, 4) == "--- " && plain_lua_name(line.substr(4))) {
      files.push_back({std::string(line.substr(4)), ""});
    } else {
      files.back().text.append(line);
      files.back().text.push_back('\n');
    }
    pos = end + 1;
  }
  return files;
}

constexpr const char* kApiManifest =
    "return { name = \"fz\", version = \"1.0\", runtime = \"runtime.lua\", scene = \"scene.lua\" "
    "}\n";

// No kit: loading it would take most of each run.
constexpr const char* kApiScene =
    R"LUA(world { dt = 1 / 120, settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } } }
object { name = "floor", position = { 0, -0.05 }, shape = "box", size = { 4, 0.1, 1 }, static = true, mass = 1 }
object { name = "ball", position = { 0, 0.11 }, shape = "sphere", radius = 0.1, mass = 1,
         probe = 1, heat = 2, dir = { 1, 0, 0 }, tag = "a", label = "x", flag = true }
object { name = "cube", position = { 0.15, 0.4 }, shape = "box", size = { 0.1, 0.1, 0.1 }, mass = 2,
         probe = 0.5, heat = 0 }
object { name = "ghost", position = { 1, 1 }, probe = 3, tag = "b" }
)LUA";

}  // namespace

// ---------------------------------------------------------------------------

void scene(const std::uint8_t* data, std::size_t size) {
  const fs::path dir = fresh_folder("scene");
  const fs::path file = dir / "scene.lua";
  write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  guarded([&] {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::LoadedScene loaded = lua::load_scene(file, registry, load_options());
    run_world(loaded, 3);
  });
}

void mod(const std::uint8_t* data, std::size_t size) {
  const std::vector<ModFile> files =
      split_mod_files(std::string_view(reinterpret_cast<const char*>(data), size));
  const fs::path dir = fresh_folder("mod") / mod_folder_name(files.front().text);
  fs::create_directories(dir);
  for (const ModFile& f : files) write_file(dir / f.name, f.text);
  guarded([&] {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::check(dir, registry, load_options());
  });
  guarded([&] {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::LoadedScene loaded = lua::load_scene(dir, registry, load_options());
    run_world(loaded, 3);
  });
}

void mod_api(const std::uint8_t* data, std::size_t size) {
  // The first bytes choose the run, the rest the programs.
  const int steps = size > 0 ? 1 + data[0] % 8 : 1;
  const int reload_at =
      size > 1 && data[1] % 3 == 0 ? data[1] / 3 % (steps + 1) : -1;  // -1: no reload
  const std::size_t skip = std::min<std::size_t>(size, 2);
  const std::string first = mod_api_program(data + skip, size - skip);
  // The second program reads the bytes backwards: a different program, as
  // long as the input.
  std::string reversed(reinterpret_cast<const char*>(data + skip), size - skip);
  std::reverse(reversed.begin(), reversed.end());
  const std::string second =
      reload_at >= 0
          ? mod_api_program(reinterpret_cast<const std::uint8_t*>(reversed.data()), reversed.size())
          : "";

  const fs::path dir = fresh_folder("api") / "fz";
  write_file(dir / "mod.lua", kApiManifest);
  write_file(dir / "scene.lua", kApiScene);
  write_file(dir / "runtime.lua", first);
  guarded([&] {
    PluginRegistry registry;
    register_native_plugins(registry);
    lua::LoadedScene loaded = lua::load_scene(dir, registry, load_options());
    World& world = *loaded.world;
    world.start();
    for (int i = 0; i < steps; ++i) {
      if (i == reload_at && loaded.mods) {
        write_file(dir / "runtime.lua", second);
        loaded.mods->reload("fz");
      }
      world.step();
      poll(loaded.mods.get());
    }
  });
}

void save(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  // Seal: what the writer would have written as checksum for these bytes
  // (pack_save's definition), so that damage inside sections is parsed.
  if (bytes.size() >= 48 && bytes.compare(0, 8, "ALLOYSAV") == 0) {
    try {
      SaveContainer c = unpack_save(bytes, "fuzz");
      (void)c;
    } catch (const InputError&) {
      // Recompute the checksum field in place; the sizes stay the fuzzer's.
      std::uint64_t meta = 0, stored = 0;
      std::memcpy(&meta, bytes.data() + 16, 8);
      std::memcpy(&stored, bytes.data() + 24, 8);
      if (meta <= bytes.size() && stored <= bytes.size() && 48 + meta + stored == bytes.size()) {
        const std::string covered = bytes.substr(0, 40) + bytes.substr(48);
        const std::uint64_t h = XXH3_64bits(covered.data(), covered.size());
        std::memcpy(bytes.data() + 40, &h, 8);
      }
    }
  }
  SaveData d;
  try {
    d = decode_save(bytes, "fuzz");
  } catch (const InputError&) {
    return;  // refused: fine
  }
  // One world per scene, loaded once: restore replaces everything in it. The
  // save names its scene; the doorbell brings the stages with their own saved
  // state (electricity, magnetism, sound, contacts, hinged assemblies), the
  // space scene the bare rigid body, rigid_demo hinges and glue.
  static PluginRegistry registry;
  static std::map<std::string, std::unique_ptr<lua::LoadedScene>> worlds;
  if (worlds.empty()) register_native_plugins(registry);
  const std::string name = d.meta.scene_name == "doorbell" || d.meta.scene_name == "rigid_demo"
                               ? d.meta.scene_name
                               : "space";
  std::unique_ptr<lua::LoadedScene>& loaded = worlds[name];
  if (!loaded) {
    lua::LoadOptions o = load_options();
    o.mod_paths.push_back(fs::path(ALLOY_SOURCE_DIR) / "mods");  // the kit; loaded once
    loaded = std::make_unique<lua::LoadedScene>(
        lua::load_scene(fs::path(ALLOY_SOURCE_DIR) / "mods" / name, registry, o));
  }
  try {
    // The save's own mod list: what is checked here is how the world reads
    // the snapshot, not which mods a player has installed.
    check_save_fits(d, "fuzz", *loaded->world, d.meta.mods, nullptr);
    loaded->world->restore(d.snapshot);
    for (int i = 0; i < 3; ++i) loaded->world->step();
  } catch (const InputError&) {
  }
}

}  // namespace alloy::fuzz
