// The palette: kit parts a player drops onto the play area. Each entry is a
// call of the Lua kit (so a part is made exactly as a scene makes it: the
// same materials, masses and defaults); the call runs as a tiny scene in a
// scratch world on the viewer's plugin registry, and its objects are copied
// into the running world through the editing API.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "apps/viewer/part_geometry.hpp"
#include "lua/scene_loader.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {

struct PaletteEntry {
  std::string label;  ///< what the button says
  std::string group;  ///< heading it is listed under
  std::string base;   ///< base of the new part's name ("steel_bar" -> steel_bar_2 if taken)
  /// Lua statements; $NAME is the part's name, $X and $Y where it is dropped
  /// (m). Other objects it makes are named $NAME_<something>.
  std::string lua;
  std::string tip;  ///< tooltip
};

/// The bundled palette: bars and disks of each material, a shelf, a pinned
/// wheel, and the electrical and magnetic parts.
const std::vector<PaletteEntry>& palette_entries();

/// Makes the entry's part in `world` at `at` and returns the ids it made, the
/// part first. Throws InputError (a kit that lacks the part, a bad entry).
std::vector<ObjectId> make_part(World& world, const PaletteEntry& entry, Vec2 at,
                                const lua::LoadOptions& options, const std::string& name);

/// Checks that the kit can make the entry (by making it in a scratch world);
/// "" if it can, else why not.
std::string check_entry(PluginRegistry& registry, const PaletteEntry& entry,
                        const lua::LoadOptions& options);

}  // namespace alloy::viewer
