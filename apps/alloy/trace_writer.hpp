// The long-format trace of `alloy run --trace FILE.csv`:
//   step,time,object,property,value
// one row per object, property and component (position.x, position.y, ...),
// values printed with round-trip precision so that two runs can be compared
// byte for byte.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/world.hpp"

namespace alloy::app {

class TraceWriter {
 public:
  /// `properties`: names to trace; each must be registered (InputError otherwise).
  TraceWriter(const std::string& path, const World& world, const std::vector<std::string>& properties);
  /// Appends the current state of every object carrying a traced property.
  void sample(const World& world);
  /// Flushes and moves the file into place (written whole: temp file + rename).
  void close();
  ~TraceWriter();

 private:
  std::string path_, temp_;
  std::ofstream out_;
  std::vector<PropertyId> props_;
  bool closed_ = false;
};

}  // namespace alloy::app
