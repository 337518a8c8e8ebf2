// What the snapshot and save benchmarks share (bench/snapshot.cpp,
// bench/saves.cpp): the falling pile they measure and the median timer.
#pragma once

#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <vector>

#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::bench {

/// The median of `reps` wall-clock timings of `f`, ms.
inline double median_ms(int reps, const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

/// The median of `reps` timings of `f` in this process's CPU time, ms: what
/// the work costs, whatever else the machine runs (wall-clock medians on a
/// machine shared by many builds are mostly waiting).
inline double median_cpu_ms(int reps, const std::function<void()>& f) {
  auto now = [] {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
  };
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const double a = now();
    f();
    t.push_back(now() - a);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

/// `boxes` boxes falling into a bin (tests/scenes, the pile of
/// alloy_bench_rigid) with every native plugin registered, let fall for
/// `settle` steps so that every box moves between two snapshots.
struct FallingPile {
  explicit FallingPile(int boxes, int settle = 5) : world(registry_with_plugins(registry), def()) {
    scenes::build_pile(world, scenes::pile_layout(boxes));
    world.run(std::uint64_t(settle));
  }
  /// A second world of the same pile, not yet stepped (to restore into).
  static void build_fresh(World& w, int boxes) {
    scenes::build_pile(w, scenes::pile_layout(boxes));
  }
  static WorldDef def() { return WorldDef{.dt = 1.0 / 240}; }

  PluginRegistry registry;
  World world;

 private:
  static PluginRegistry& registry_with_plugins(PluginRegistry& r) {
    register_native_plugins(r);
    return r;
  }
};

}  // namespace alloy::bench
