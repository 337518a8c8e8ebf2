// Per-stage and per-phase timing of World::step (what `alloy run --profile` prints).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/stage.hpp"

namespace alloy {

struct StageTiming {
  std::string name;
  StageKind kind = StageKind::Resolver;
  std::uint64_t runs = 0;     ///< times the stage ran
  std::uint64_t skipped = 0;  ///< times it was due but skipped (inputs unchanged, or `every`)
  double seconds = 0;         ///< wall time spent in the stage
};

struct PhaseTiming {
  double advance = 0, derive = 0, interact = 0, publish = 0, edits = 0;
  double total() const { return advance + derive + interact + publish + edits; }
};

struct Profile {
  std::uint64_t steps = 0;
  PhaseTiming phases;
  std::vector<StageTiming> stages;             ///< active stages, in run order
  std::vector<std::string> not_instantiated;  ///< available plugins that no object needs
};

/// Monotonic wall clock in seconds, for timing phases.
inline double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace alloy
