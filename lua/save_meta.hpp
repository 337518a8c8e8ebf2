// The meta block of a save file or recording of a loaded scene (the scene's
// path, its name, the registry's types and plugins, the mods with their
// versions): one place for the commands (`alloy run --save/--record`) and
// the viewer (`alloy view --record`).
#pragma once

#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "runtime/save_file.hpp"

namespace alloy::lua {

/// The mods `scene` loaded, with the versions their manifests give (the
/// scene's own mod first, if `path` is a mod folder).
std::vector<SaveMeta::Mod> scene_mods(const LoadedScene& scene, const LoadOptions& load,
                                      const std::string& path);

/// The meta block of a save or recording of `scene`, loaded from `path`
/// (stored absolute, so that `alloy replay` finds it from anywhere).
SaveMeta save_meta(const LoadedScene& scene, const LoadOptions& load, const std::string& path);

}  // namespace alloy::lua
