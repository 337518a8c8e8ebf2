// What a scene's Lua code leaves behind: the world settings and the objects it
// asked for, each with the line that asked, in plain C++ values. Recording is
// the first half of loading (collect, then apply): the scene runs to the end
// without touching a World, and scene_builder.hpp turns the record into one.
// Nothing here knows Lua.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "runtime/error.hpp"

namespace alloy::lua {

/// A value as a script wrote it, before it is typed against the property
/// registry: lists stay lists until the builder knows whether a vec3, a quat
/// or a list of names is wanted.
using SceneValue =
    std::variant<double, bool, std::string, std::vector<double>, std::vector<std::string>>;

/// Human name of what a script wrote ("a number", "a list of 2 numbers").
std::string describe(const SceneValue& v);

struct SceneField {
  std::string key;
  SceneValue value;
};

struct RecordedObject {
  std::string name;                ///< may be empty
  ErrorLocation where;             ///< file and line of the statement; object = name or "#n"
  std::vector<SceneField> fields;  ///< sorted by key, without `name`
};

struct RecordedSettings {
  std::string plugin;
  std::vector<SceneField> fields;
};

/// One entry of world{ areas = {...} }.
struct RecordedArea {
  std::string name;
  std::vector<SceneField> region;  ///< center, half_extents, radius as written
  std::vector<std::string> plugins;
  std::vector<RecordedSettings> settings;
};

struct RecordedWorld {
  bool given = false;   ///< world{} was called
  ErrorLocation where;  ///< line of the world{} statement
  std::string name;
  std::string description;
  std::optional<double> dt;
  double seconds = 0;
  std::vector<std::string> plugins;
  std::vector<RecordedSettings> settings;
  std::vector<std::pair<std::string, double>> every;
  std::vector<std::pair<std::string, std::string>> use;  ///< thing -> plugin
  std::vector<std::string> report;  ///< "object.property[.component][@seconds]" for the CLI
  std::vector<RecordedArea> areas;
  /// grants = { mod = { "property", ... } }: properties of others a mod's
  /// resolvers may write (mod_runtime.hpp, WriteGrant), sorted by mod.
  std::vector<std::pair<std::string, std::vector<std::string>>> grants;
};

/// `swap(time, "area" or "", "from", "to")`: a resolver swap on the timeline.
struct RecordedSwap {
  double time = 0;
  std::string area, from, to;
  ErrorLocation where;
};

/// `at(time, "object", { property = value, ... })`: values to set on a named
/// object when the world reaches `time` (the scene's timeline of input).
struct RecordedInput {
  double time = 0;
  std::string object;
  ErrorLocation where;  ///< line of the at() statement; object = the target's name
  std::vector<SceneField> fields;
};

struct SceneRecord {
  RecordedWorld world;
  std::vector<RecordedObject> objects;
  std::vector<RecordedInput> inputs;
  std::vector<RecordedSwap> swaps;
};

}  // namespace alloy::lua
