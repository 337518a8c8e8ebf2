// What a headless run of a bundled scene leaves for a test to read: its
// events as plain records with objects by name. Shared by the doorbell and
// motor tests (and motor_study).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "runtime/world.hpp"

namespace alloy::test {

/// A path in the source tree (mods/doorbell, ...).
inline std::filesystem::path source(const std::string& relative) {
  return std::filesystem::path(ALLOY_SOURCE_DIR) / relative;
}

/// An event with its objects by name.
struct Record {
  std::uint64_t step = 0;
  double time = 0;
  std::string type, a, b;
  std::vector<std::pair<std::string, double>> values;
  double value(const std::string& key) const {
    for (const auto& [k, v] : values)
      if (k == key) return v;
    return NAN;
  }
};

/// The events of a run, in order.
struct EventRecords {
  std::vector<Record> events;

  /// Records every event `world` publishes from now on; this object must
  /// outlive the world's stepping.
  void record(World& world) {
    world.add_observer([this, &world](const Event& e) {
      events.push_back({e.step, e.time, e.type, e.a ? world.describe(e.a) : "",
                        e.b ? world.describe(e.b) : "", e.values});
    });
  }
  /// The events of `type`, concerning object `a` if given.
  std::vector<const Record*> of(const std::string& type, const std::string& a = "") const {
    std::vector<const Record*> out;
    for (const auto& e : events)
      if (e.type == type && (a.empty() || e.a == a)) out.push_back(&e);
    return out;
  }
};

}  // namespace alloy::test
