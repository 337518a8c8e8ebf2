#include "lua/save_meta.hpp"

#include <filesystem>

#include "lua/lua_host.hpp"
#include "lua/mod_loader.hpp"
#include "lua/mod_runtime.hpp"

namespace alloy::lua {

/// The mods a scene loaded, with the versions their manifests give (the
/// scene's own mod first, if the scene is a mod folder).
std::vector<SaveMeta::Mod> scene_mods(const LoadedScene& scene, const LoadOptions& load,
                                      const std::string& path) {
  std::vector<SaveMeta::Mod> mods;
  LuaHost host;
  std::error_code ec;
  auto add = [&](const std::filesystem::path& folder) {
    const Manifest m = read_manifest(host, folder);
    for (const auto& x : mods)
      if (x.name == m.name) return;
    mods.push_back({m.name, m.version});
  };
  if (std::filesystem::is_directory(path, ec)) add(path);
  if (scene.mods)
    for (const std::string& name : scene.mods->loaded())
      for (const auto& dir : load.mod_paths)
        if (std::filesystem::exists(dir / name / "mod.lua", ec)) {
          add(dir / name);
          break;
        }
  return mods;
}

/// The meta block of a save or recording of `scene`, loaded from `path`.
SaveMeta save_meta(const LoadedScene& scene, const LoadOptions& load, const std::string& path) {
  SaveMeta meta = describe_world(*scene.world);
  std::error_code ec;
  const auto abs = std::filesystem::absolute(path, ec);
  meta.scene = ec ? path : abs.lexically_normal().string();
  meta.scene_name = scene.name;
  meta.mods = scene_mods(scene, load, path);
  return meta;
}

}  // namespace alloy::lua
