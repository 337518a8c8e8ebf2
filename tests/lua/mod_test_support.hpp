// Helpers for the tests of Lua mods: a temporary folder of mods that a test
// writes (and rewrites, while a world runs), and a world with the native
// plugins and a ModRuntime over it.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "lua/mod_runtime.hpp"
#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "tests/lua/lua_test_support.hpp"

namespace alloy::test {

/// A folder under the system's temp directory, removed with everything in it.
class TempMods {
 public:
  TempMods() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("alloy_mods_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempMods() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempMods(const TempMods&) = delete;
  TempMods& operator=(const TempMods&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& rel) const { return path_ / rel; }

  /// Writes `text` to `rel` whole (temp file + rename, as editors do).
  void write(const std::string& rel, const std::string& text) const {
    const auto file = path_ / rel;
    std::filesystem::create_directories(file.parent_path());
    const auto tmp = file.string() + ".tmp~";
    {
      std::ofstream out(tmp, std::ios::binary);
      out << text;
    }
    std::filesystem::rename(tmp, file);
  }

  /// A mod folder with a manifest naming runtime.lua, and its runtime file.
  void mod(const std::string& name, const std::string& runtime,
           const std::string& extra_manifest = "") const {
    write(name + "/mod.lua", "return { name = \"" + name +
                                 "\", version = \"1.0\", runtime = \"runtime.lua\"" +
                                 (extra_manifest.empty() ? "" : ", " + extra_manifest) + " }\n");
    write(name + "/runtime.lua", runtime);
  }

 private:
  std::filesystem::path path_;
};

/// The options of a ModRuntime over `mods`, with the log kept for the test.
/// The well-behaved mod of the sandbox and hostile tests: its resolver adds
/// one to `good_count` every step, so a count equal to the steps run shows
/// that the world, and this mod with it, went on whatever another mod did.
inline constexpr const char* kGood = R"LUA(
mod.property { name = "good_count" }
mod.resolver {
  name = "good.counter", writes = { "good_count" }, needs = { "good_count" },
  advance = function(w) local c = w:write("good_count") for i in c:each() do c[i] = c[i] + 1 end end,
}
)LUA";

inline lua::ModRuntimeOptions runtime_options(const TempMods& mods, std::vector<std::string>* log) {
  lua::ModRuntimeOptions o;
  o.mod_paths = {mods.path(), source_path("mods")};
  o.log = [log](const std::string& mod, const std::string& line) {
    if (log) log->push_back("[" + mod + "] " + line);
  };
  return o;
}

/// Whether any event of the world's last step has this type.
inline const Event* find_event(const World& world, const std::string& type) {
  for (const Event& e : world.events())
    if (e.type == type) return &e;
  return nullptr;
}

/// The reports of stages disabled and mods stopped since the last poll, one
/// a line ("" if none).
inline std::string stage_failures(lua::ModRuntime& runtime) {
  std::string text;
  for (const auto& r : runtime.poll())
    if (r.kind == lua::ModReport::Kind::StageDisabled || r.kind == lua::ModReport::Kind::Stopped)
      text += r.message + "\n";
  return text;
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace alloy::test
