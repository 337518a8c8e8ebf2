// Saving a running world as a scene that `alloy run` and `alloy view` load
// again: a Lua file of one world{} statement and one raw object{} per object,
// every property the object carries written out (positions, velocities and
// currents as they are now), references by name. Nothing here knows SDL.
#pragma once

#include <filesystem>
#include <string>

#include "runtime/world.hpp"

namespace alloy::viewer {

struct SceneMeta {
  std::string name;         ///< world{ name }
  std::string description;  ///< world{ description }
  double seconds = 0;       ///< world{ seconds }, 0 = not written
  std::string origin;       ///< where the world came from, for the header comment
};

/// How every scene the writer writes begins (its first line's start): how
/// the viewer tells its own files, which Save writes over, from scenes
/// written by hand, which it saves beside.
inline constexpr const char* kSavedHeader = "-- Saved by `alloy view`";

/// The scene as Lua text. Objects without a name that another object refers
/// to are named "_<slot>" so that the reference can be written.
std::string write_scene(const World& world, const SceneMeta& meta);

/// Writes the scene whole: to a temporary file beside `path`, then renamed
/// over it, so that a reader never sees half a file. Throws
/// std::runtime_error naming the path.
void save_scene(const World& world, const SceneMeta& meta, const std::filesystem::path& path);

/// Writes `data` to `path` through a temporary file and a rename.
void write_file_whole(const std::filesystem::path& path, const std::string& data);

}  // namespace alloy::viewer
