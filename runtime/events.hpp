// Events: what happened in a step (contact began, circuit closed, bell struck).
// Stages record events while they run; the world publishes them after the step
// (Box2D's b2World_GetContactEvents model): observers never run inside a stage.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/object_id.hpp"

namespace alloy {

struct Event {
  /// The step the event happened in, counted from 1 (0: before the first step,
  /// while the world primed itself); filled by the world at publish.
  std::uint64_t step = 0;
  double time = 0;  ///< simulated time at the end of that step, s; filled by the world
  std::string type;        ///< e.g. "contact_began", "circuit_closed"
  std::string source;      ///< the stage that emitted it; filled by the world
  ObjectId a{}, b{};       ///< the objects concerned, if any
  /// Named numbers (impulse, current, ...), in the order given.
  std::vector<std::pair<std::string, double>> values;
  std::string text;  ///< optional free text

  double value(std::string_view key, double fallback = 0) const {
    for (const auto& [k, v] : values)
      if (k == key) return v;
    return fallback;
  }
};

}  // namespace alloy
