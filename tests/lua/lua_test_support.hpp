// Helpers shared by the Lua tests: paths in the source tree and typed reads.
#pragma once

#include <filesystem>
#include <string>

#include "runtime/world.hpp"

namespace alloy::test {

inline std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(ALLOY_SOURCE_DIR) / relative;
}

template <class T>
T get(const World& world, const std::string& object, const std::string& property) {
  const ObjectId id = world.find(object);
  if (!id) throw std::runtime_error("no object " + object);
  return std::get<T>(world.get(id, property));
}

inline bool has(const World& world, const std::string& object, const std::string& property) {
  const ObjectId id = world.find(object);
  auto p = world.properties().find(property);
  return id && p && world.store().has(id, *p);
}

}  // namespace alloy::test
